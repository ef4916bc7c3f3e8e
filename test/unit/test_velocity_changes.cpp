// VelocityChanges: the running second moment of a camera's velocity changes.
#include <limits>

#include <gtest/gtest.h>

#include "acvo/odometry/velocity_changes.hpp"

namespace acvo {
namespace {

TEST(VelocityChanges, AveragesTheFirstSamplesThenForgetsOverItsMemory) {
  VelocityChanges changes(4.0);
  EXPECT_EQ(changes.count(), 0);
  EXPECT_TRUE(changes.moment().isZero());
  Vector6d a = Vector6d::Zero(), b = Vector6d::Zero();
  a[0] = 2.0;
  b[3] = 1.0;
  changes.add(a);
  changes.add(b);
  // The mean of the two outer products.
  EXPECT_DOUBLE_EQ(changes.moment()(0, 0), 2.0);
  EXPECT_DOUBLE_EQ(changes.moment()(3, 3), 0.5);
  EXPECT_DOUBLE_EQ(changes.moment()(0, 3), 0.0);
  // A sample that is not finite is not one.
  changes.add(Vector6d::Constant(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(changes.count(), 2);
  // Past the memory, each sample moves the moment by a quarter of its difference.
  for (int k = 0; k < 2; ++k) changes.add(b);
  const double before = changes.moment()(0, 0);
  changes.add(b);
  EXPECT_DOUBLE_EQ(changes.moment()(0, 0), 0.75 * before);
  changes.reset();
  EXPECT_EQ(changes.count(), 0);
  EXPECT_TRUE(changes.moment().isZero());
}

}  // namespace
}  // namespace acvo
