// Inputs found by the fuzzers (fuzz/, scripts/test --fuzz) that once hung the core or broke one
// of its contracts, each reduced to the smallest case that shows the fault.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/registration/kernel.hpp"
#include "acvo/dataset/tum.hpp"
#include "test_support.hpp"

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A 64x48 textured frame of a wall 2 m away, with the given intrinsics.
acvo::Frame wallFrame(double fx, double fy, double cx, double cy) {
  acvo::Frame f;
  f.camera.fx = fx, f.camera.fy = fy, f.camera.cx = cx, f.camera.cy = cy;
  f.camera.width = 64, f.camera.height = 48, f.camera.depth_scale = 1.0;
  f.color.create(48, 64, CV_8UC3);
  cv::RNG rng(7);
  rng.fill(f.color, cv::RNG::UNIFORM, 0, 256);
  f.depth = cv::Mat(48, 64, CV_32FC1, cv::Scalar(2.0));
  f.order = acvo::ColorOrder::kBgr;
  return f;
}

std::vector<int> candidatesOf(const acvo::VoxelGrid& grid, const Eigen::Vector3f& q) {
  std::vector<int> found;
  grid.forEachCandidate(q, [&](int i, const Eigen::Vector3f& /*x*/) { found.push_back(i); });
  return found;
}

// The grid once sized its cells with hi - lo in float: points near the float range overflowed
// it to infinity and the loop that coarsens the cells never ended.
TEST(FuzzRegression, VoxelGridOverPointsNearTheFloatRange) {
  const std::vector<Eigen::Vector3f> points = {
      {-3e38f, 0.f, 1.f}, {3e38f, 0.f, 1.f}, {0.f, 0.f, 1.f}, {0.f, 0.f, 1.f}};
  const acvo::VoxelGrid grid(points, 0.2f);
  ASSERT_FALSE(grid.empty());
  // Coarsened by factors of 1.5 just enough to span 6e38 m along x with the columns 4 points
  // may have.
  const double columns = acvo::VoxelGrid::maxColumns(points.size());
  EXPECT_GE(grid.cell(), 6e38 / columns);
  EXPECT_LT(grid.cell(), 1.5 * 6e38 / columns);
  EXPECT_LE(grid.columns(), columns);
  std::vector<int> near_origin = candidatesOf(grid, {0.f, 0.f, 1.f});
  EXPECT_NE(std::find(near_origin.begin(), near_origin.end(), 2), near_origin.end());
  EXPECT_NE(std::find(near_origin.begin(), near_origin.end(), 3), near_origin.end());
}

// Non-finite points (and a bounding box from them) made the loop endless too; they now stay out
// of the grid, and non-finite or far-away queries find nothing.
TEST(FuzzRegression, VoxelGridLeavesNonFinitePointsOut) {
  const std::vector<Eigen::Vector3f> points = {
      {kInf, 0.f, 1.f}, {0.f, 0.f, 1.f}, {kNaN, 0.f, 1.f}, {0.05f, 0.f, 1.f}, {-kInf, 0.f, 1.f}};
  const acvo::VoxelGrid grid(points, 0.2f);
  ASSERT_FALSE(grid.empty());
  EXPECT_EQ(grid.cell(), 0.2f);  // the finite points alone set the extent
  std::vector<int> found = candidatesOf(grid, {0.f, 0.f, 1.f});
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found, (std::vector<int>{1, 3}));
  EXPECT_TRUE(candidatesOf(grid, {kNaN, 0.f, 1.f}).empty());
  EXPECT_TRUE(candidatesOf(grid, {kInf, 0.f, 1.f}).empty());
  EXPECT_TRUE(candidatesOf(grid, {1e30f, 0.f, 1.f}).empty());  // beyond int cell indices

  const acvo::VoxelGrid none({{kNaN, kNaN, kNaN}}, 0.2f);
  EXPECT_TRUE(none.empty());
}

// Intrinsics that pass Camera::valid() but put the back-projected points beyond the float range
// (a principal point of 1e300 pixels, a focal length of 2e-37): Odometry::process never returned.
TEST(FuzzRegression, OdometryOnIntrinsicsBeyondTheFloatRange) {
  for (const acvo::Frame& frame :
       {wallFrame(50.0, 50.0, 1e300, 24.0), wallFrame(2e-37, 50.0, 32.0, 24.0)}) {
    ASSERT_TRUE(frame.problem().empty());
    acvo::Params params;
    params.odometry.threads = 1;
    acvo::Odometry odometry(params);
    EXPECT_EQ(odometry.process(frame).tracking, acvo::Tracking::kFirstFrame);
    const acvo::OdometryResult r = odometry.process(frame);
    EXPECT_NE(r.tracking, acvo::Tracking::kBadFrame);
    EXPECT_TRUE(r.pose.matrix().allFinite());
    EXPECT_TRUE(r.motion_covariance.allFinite());
  }
}

// A number field with a NUL byte inside ("130503110\0\0...") was read as the number before the
// NUL: strtod stops there and the parser only checked that it stopped at a NUL.
TEST(FuzzRegression, NumberFieldsWithANulByteAreMalformed) {
  const auto dir = acvo::test::tempDir("fuzz_regression_nul");
  const std::string nul(1, '\0');
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return (dir / name).string();
  };
  EXPECT_THROW(acvo::readTumList(write("rgb.txt", "1305031102.5" + nul + "7 rgb/a.png\n")),
               std::runtime_error);
  EXPECT_THROW(acvo::readAssociations(
                   write("associations.txt", "1.0 rgb/a.png 1.0" + nul + nul + " depth/a.png\n")),
               std::runtime_error);
  EXPECT_THROW(acvo::readTrajectory(write("trajectory.txt", "1.0 0 0 0" + nul + "5 0 0 0 1\n")),
               std::runtime_error);
  // The same lines without the NUL bytes are fine.
  EXPECT_EQ(acvo::readTumList(write("rgb_ok.txt", "1305031102.57 rgb/a.png\n")).size(), 1u);
  EXPECT_EQ(acvo::readTrajectory(write("trajectory_ok.txt", "1.0 0 0 0 0 0 0 1\n")).size(), 1u);
}

}  // namespace
