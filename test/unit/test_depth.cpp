// Depth decoding: every raw encoding gives the same metres; invalid pixels become 0. A depth
// image seen from another pose: each point where the moved camera sees it, the nearest kept.
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <tuple>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/rgbd/depth.hpp>

#include "acvo/cloud/depth.hpp"
#include "acvo/math/se3.hpp"
#include "acvo/dataset/tum.hpp"
#include "test_support.hpp"

namespace {

// Depths in metres that every encoding below represents exactly enough: multiples of 1 mm.
const float kMetres[] = {0.5f, 1.234f, 2.0f, 4.321f, 7.999f, 0.001f};
constexpr int kCount = sizeof(kMetres) / sizeof(kMetres[0]);

TEST(Depth, TumPngMillimetresAndMetresGiveTheSameMetres) {
  cv::Mat tum(2, 3, CV_16UC1), mm(2, 3, CV_16UC1), m(2, 3, CV_32FC1);
  for (int k = 0; k < kCount; ++k) {
    tum.at<std::uint16_t>(k / 3, k % 3) =
        static_cast<std::uint16_t>(std::lround(kMetres[k] * 5000.0));
    mm.at<std::uint16_t>(k / 3, k % 3) =
        static_cast<std::uint16_t>(std::lround(kMetres[k] * 1000.0));
    m.at<float>(k / 3, k % 3) = kMetres[k];
  }
  // The TUM encoding goes through a real PNG file, as the datasets store it.
  const auto png = (acvo::test::tempDir("depth_png") / "depth.png").string();
  ASSERT_TRUE(cv::imwrite(png, tum));
  const cv::Mat tum_read = cv::imread(png, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(tum_read.type(), CV_16UC1);

  const cv::Mat from_tum = acvo::depthToMeters(tum_read, 5000.0);
  const cv::Mat from_mm = acvo::depthToMeters(mm, 1000.0);
  const cv::Mat from_m = acvo::depthToMeters(m, 1.0);
  for (const cv::Mat* out : {&from_tum, &from_mm, &from_m}) {
    ASSERT_EQ(out->type(), CV_32FC1);
    ASSERT_EQ(out->size(), cv::Size(3, 2));
    for (int k = 0; k < kCount; ++k) {
      EXPECT_NEAR(out->at<float>(k / 3, k % 3), kMetres[k], 1e-6) << "pixel " << k;
    }
  }
}

TEST(Depth, InvalidPixelsBecomeZero) {
  // 0, and 65535: 7-Scenes' mark of a pixel without a reading.
  cv::Mat raw16 = (cv::Mat_<std::uint16_t>(1, 4) << 0, 10000, 65535, 65534);
  for (double scale : {5000.0, 1000.0}) {
    const cv::Mat out16 = acvo::depthToMeters(raw16, scale);
    EXPECT_EQ(out16.at<float>(0, 0), 0.0f) << scale;
    EXPECT_EQ(out16.at<float>(0, 2), 0.0f) << scale;
  }
  const cv::Mat out16 = acvo::depthToMeters(raw16, 5000.0);
  EXPECT_FLOAT_EQ(out16.at<float>(0, 1), 2.0f);
  EXPECT_FLOAT_EQ(out16.at<float>(0, 3), 65534.0f / 5000.0f);

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  cv::Mat raw32 = (cv::Mat_<float>(1, 6) << 0.0f, nan, inf, -inf, -1.5f, 3.25f);
  const cv::Mat out32 = acvo::depthToMeters(raw32, 1.0);
  for (int u = 0; u < 5; ++u) EXPECT_EQ(out32.at<float>(0, u), 0.0f) << "column " << u;
  EXPECT_FLOAT_EQ(out32.at<float>(0, 5), 3.25f);
}

TEST(Depth, WrongTypeOrScaleThrows) {
  EXPECT_THROW(acvo::depthToMeters(cv::Mat(2, 2, CV_8UC1, cv::Scalar(1)), 1.0),
               std::invalid_argument);
  EXPECT_THROW(acvo::depthToMeters(cv::Mat(2, 2, CV_16UC3, cv::Scalar(1, 1, 1)), 5000.0),
               std::invalid_argument);
  EXPECT_THROW(acvo::depthToMeters(cv::Mat(2, 2, CV_64FC1, cv::Scalar(1)), 1.0),
               std::invalid_argument);
  EXPECT_THROW(acvo::depthToMeters(cv::Mat(2, 2, CV_16UC1, cv::Scalar(1)), 0.0),
               std::invalid_argument);
  EXPECT_THROW(acvo::depthToMeters(cv::Mat(2, 2, CV_16UC1, cv::Scalar(1)),
                                   std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
}

// A small camera with round numbers: pixel shifts of f * t / z are whole pixels.
acvo::Camera smallCamera() {
  acvo::Camera c;
  c.fx = c.fy = 500.0;
  c.cx = 79.5;
  c.cy = 59.5;
  c.width = 160;
  c.height = 120;
  return c;
}

TEST(DepthSeenFrom, EachPointLandsWhereTheMovedCameraSeesIt) {
  const acvo::Camera c = smallCamera();
  acvo::Vector6d xi;
  xi << 0.02, -0.03, 0.01, 0.05, -0.02, 0.04;
  const Eigen::Isometry3d moved = acvo::expSE3(xi);
  for (const auto& [u, v, z] : {std::tuple{40, 30, 1.5f}, std::tuple{100, 90, 0.8f}}) {
    cv::Mat depth(c.height, c.width, CV_32FC1, cv::Scalar(0.0f));
    depth.at<float>(v, u) = z;
    const Eigen::Vector3d p = moved.inverse() * c.backProject(u, v, z);
    const Eigen::Vector2d px = c.project(p);
    const cv::Mat out = acvo::depthSeenFrom(depth, c, moved);
    ASSERT_EQ(out.type(), CV_32FC1);
    ASSERT_EQ(cv::countNonZero(out), 1);
    const int pu = int(std::lround(px.x())), pv = int(std::lround(px.y()));
    EXPECT_NEAR(out.at<float>(pv, pu), p.z(), 1e-6) << "pixel " << u << ", " << v;
    EXPECT_GT(std::abs(pu - u) + std::abs(pv - v), 5) << "the test's motion moves the point";
  }
}

TEST(DepthSeenFrom, NotMovedIsTheSameImageAndInvalidDepthStaysOut) {
  const acvo::Camera c = smallCamera();
  cv::Mat depth(c.height, c.width, CV_32FC1, cv::Scalar(2.0f));
  depth(cv::Rect(10, 10, 20, 20)) = 0.0f;
  depth.at<float>(50, 50) = std::numeric_limits<float>::quiet_NaN();
  const cv::Mat out = acvo::depthSeenFrom(depth, c, Eigen::Isometry3d::Identity());
  cv::Mat expected = depth.clone();
  expected.at<float>(50, 50) = 0.0f;
  EXPECT_EQ(cv::norm(out, expected, cv::NORM_INF), 0.0);
}

TEST(DepthSeenFrom, TheNearerSurfaceHidesTheFarther) {
  // The camera moves 0.1 m to the right: a point at 1 m moves 50 px left in the image, one at
  // 2 m 25 px. Pixel 100 at 1 m and pixel 75 at 2 m both land on pixel 50.
  const acvo::Camera c = smallCamera();
  cv::Mat depth(c.height, c.width, CV_32FC1, cv::Scalar(0.0f));
  depth.at<float>(60, 100) = 1.0f;
  depth.at<float>(60, 75) = 2.0f;
  const Eigen::Isometry3d moved(Eigen::Translation3d(0.1, 0.0, 0.0));
  const cv::Mat out = acvo::depthSeenFrom(depth, c, moved);
  EXPECT_EQ(cv::countNonZero(out), 1);
  EXPECT_FLOAT_EQ(out.at<float>(60, 50), 1.0f);
  // A plane 2 m ahead seen 0.1 m nearer: 1.9 m wherever something lands, the view filled but
  // for the cracks between spread pixels and the border the move uncovers.
  const cv::Mat plane = acvo::depthSeenFrom(cv::Mat(c.height, c.width, CV_32FC1, 2.0f), c,
                                            Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.1)));
  const cv::Mat landed = plane > 0.0f;
  EXPECT_GT(cv::countNonZero(landed), int(0.85 * c.width * c.height));
  double lo = 0.0, hi = 0.0;
  cv::minMaxLoc(plane, &lo, &hi, nullptr, nullptr, landed);
  EXPECT_NEAR(lo, 1.9, 1e-5);
  EXPECT_NEAR(hi, 1.9, 1e-5);
}

TEST(DepthSeenFrom, AgreesWithOpenCVsRegisterDepthOnARealFrame) {
  const auto data = acvo::test::sharedDataDir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent";
  const acvo::TumDataset tum((data / "tum_fr3_teddy200").string());
  const acvo::Frame frame = tum.loadFrame(0);
  acvo::Vector6d xi;  // 2 ms of teddy200's fastest turn (100 deg/s) and 1 mm
  xi << 0.0035, 0.001, -0.0005, 0.001, 0.0, 0.0005;
  const Eigen::Isometry3d moved = acvo::expSE3(xi);
  const cv::Mat ours = acvo::depthSeenFrom(frame.depth, frame.camera, moved);

  cv::Mat nan_holes = frame.depth.clone();  // registerDepth's float images mark holes by NaN
  nan_holes.setTo(std::numeric_limits<float>::quiet_NaN(), frame.depth == 0.0f);
  const cv::Matx33d K(frame.camera.fx, 0, frame.camera.cx, 0, frame.camera.fy, frame.camera.cy, 0,
                      0, 1);
  cv::Matx44d Rt;
  const Eigen::Matrix4d to_moved = moved.inverse().matrix();
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k) Rt(r, k) = to_moved(r, k);
  cv::Mat theirs;
  cv::rgbd::registerDepth(K, K, cv::Mat::zeros(5, 1, CV_64F), Rt, nan_holes, frame.depth.size(),
                          theirs, false);
  cv::patchNaNs(theirs, 0.0);
  int both = 0, agree = 0, only_one = 0;
  for (int v = 0; v < ours.rows; ++v) {
    for (int u = 0; u < ours.cols; ++u) {
      const float a = ours.at<float>(v, u), b = theirs.at<float>(v, u);
      if ((a > 0.0f) != (b > 0.0f)) ++only_one;
      if (a > 0.0f && b > 0.0f) {
        ++both;
        agree += std::abs(a - b) < 1e-4f;
      }
    }
  }
  ASSERT_GT(both, 200000);
  EXPECT_GT(agree, 0.99 * both) << agree << " of " << both;
  EXPECT_LT(only_one, 0.01 * both);
}

TEST(DepthSeenFrom, WrongTypeOrSizeThrows) {
  const acvo::Camera c = smallCamera();
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  EXPECT_THROW(acvo::depthSeenFrom(cv::Mat(c.height, c.width, CV_16UC1, cv::Scalar(1)), c, I),
               std::invalid_argument);
  EXPECT_THROW(acvo::depthSeenFrom(cv::Mat(c.height, c.width + 1, CV_32FC1, 1.0f), c, I),
               std::invalid_argument);
}

}  // namespace
