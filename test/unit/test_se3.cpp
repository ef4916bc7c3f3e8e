// SE(3) exp/log: the properties the solver relies on (docs/method.md §3).
#include <random>

#include <gtest/gtest.h>

#include "acvo/math/se3.hpp"
#include "se3_fixtures.hpp"

namespace acvo {
namespace {

using test::randomTwist;

TEST(Se3, ExpOfLogIsIdentityMap) {
  std::mt19937 rng(1);
  for (double rot : {0.0, 1e-9, 1e-5, 1e-2, 0.5, 2.0, 3.1}) {
    for (int k = 0; k < 20; ++k) {
      const Eigen::Isometry3d T = expSE3(randomTwist(rng, rot, 0.5));
      const Eigen::Isometry3d back = expSE3(logSE3(T));
      EXPECT_LT((back.matrix() - T.matrix()).norm(), 1e-12) << "rot scale " << rot;
    }
  }
}

TEST(Se3, LogOfExpNearPiAndZero) {
  Vector6d xi;
  xi << 0, 0, M_PI - 1e-7, 0.1, -0.2, 0.3;
  EXPECT_LT((logSE3(expSE3(xi)) - xi).norm(), 1e-6);
  xi << 1e-10, -2e-10, 3e-10, 1, 2, 3;
  EXPECT_LT((logSE3(expSE3(xi)) - xi).norm(), 1e-14);
}

TEST(Se3, OneParameterSubgroup) {
  std::mt19937 rng(2);
  for (int k = 0; k < 50; ++k) {
    const Vector6d xi = randomTwist(rng, 0.4, 0.3);
    const double a = 0.37, b = -1.2;
    const Eigen::Isometry3d lhs = expSE3(a * xi) * expSE3(b * xi);
    EXPECT_LT((lhs.matrix() - expSE3((a + b) * xi).matrix()).norm(), 1e-12);
  }
}

TEST(Se3, PureTranslationIsExact) {
  Vector6d xi;
  xi << 0, 0, 0, 0.123456789, -2.5, 1e-9;
  const Eigen::Isometry3d T = expSE3(0.3 * xi);
  EXPECT_EQ(T.translation(), Eigen::Vector3d(0.3 * 0.123456789, 0.3 * -2.5, 0.3 * 1e-9));
  EXPECT_EQ(T.linear(), Eigen::Matrix3d::Identity());
}

TEST(Se3, RotationStaysOrthonormalAfterManyUpdates) {
  std::mt19937 rng(3);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int k = 0; k < 10000; ++k) T = normalized(expSE3(randomTwist(rng, 0.05, 0.01)) * T);
  const Eigen::Matrix3d R = T.linear();
  EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

TEST(Se3, ExpMatchesRodriguesForKnownRotation) {
  Vector6d xi;
  xi << 0, 0, M_PI / 2, 0, 0, 0;
  const Eigen::Isometry3d T = expSE3(xi);
  EXPECT_LT((T * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-15);
}

TEST(Se3, LeftJacobianInverseIsTheDerivativeOfTheLogUnderALeftPerturbation) {
  // J^-1(xi) a = d log(exp(a) exp(xi)) / da, checked by central differences at small and large
  // angles (the series branch below 0.1 rad and the closed form above it).
  std::mt19937 rng(7);
  for (const double rot : {1e-4, 0.03, 0.4, 1.5}) {
    const Vector6d xi = randomTwist(rng, rot, 0.5);
    const Eigen::Isometry3d T = expSE3(xi);
    const Matrix6d J = leftJacobianInverseSE3(xi);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      const Vector6d e = Vector6d::Unit(k) * h;
      const Vector6d numeric = (logSE3(expSE3(e) * T) - logSE3(expSE3(-e) * T)) / (2.0 * h);
      EXPECT_LT((numeric - J.col(k)).norm(), 1e-7) << "angle " << xi.head<3>().norm() << " column " << k;
    }
  }
}

}  // namespace
}  // namespace acvo
