// Depth decoding: every raw encoding gives the same metres; invalid pixels become 0.
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "acvo/depth.hpp"
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
  cv::Mat raw16 = (cv::Mat_<std::uint16_t>(1, 2) << 0, 10000);
  const cv::Mat out16 = acvo::depthToMeters(raw16, 5000.0);
  EXPECT_EQ(out16.at<float>(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(out16.at<float>(0, 1), 2.0f);

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

}  // namespace
