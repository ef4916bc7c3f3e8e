// Depth decoding: TUM 16-bit PNG (units per metre from the camera), 16UC1 millimetres and
// 32FC1 metres go through one code path, in the spirit of depth_image_proc's DepthTraits.
#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"

namespace acvo {

template <typename T>
struct DepthTraits;

template <>
struct DepthTraits<std::uint16_t> {
  static constexpr int cv_type = CV_16UC1;
  // 0, and the largest value: the no-reading mark of 7-Scenes' depth (13 m in TUM's units, 65 m
  // in millimetres, beyond every RGB-D camera's range).
  static constexpr std::uint16_t kNoReading = 0xFFFF;
  static bool valid(std::uint16_t raw) { return raw != 0 && raw != kNoReading; }
  static float toMeters(std::uint16_t raw, double units_per_metre) {
    return static_cast<float>(raw / units_per_metre);
  }
};

template <>
struct DepthTraits<float> {
  static constexpr int cv_type = CV_32FC1;
  static bool valid(float raw) { return std::isfinite(raw) && raw != 0.0f; }
  static float toMeters(float raw, double units_per_metre) {
    return static_cast<float>(raw / units_per_metre);
  }
};

// Converts a raw depth image (CV_16UC1 or CV_32FC1) to metres (CV_32FC1), with 0 for every
// invalid pixel (raw 0 or 65535, NaN, Inf, negative). `units_per_metre`: 5000 for TUM PNG, 1000 for
// 16UC1 millimetres, 1 for 32FC1 metres. Throws std::invalid_argument for other types.
cv::Mat depthToMeters(const cv::Mat& raw, double units_per_metre);

// The depth image (CV_32FC1 metres, 0 = invalid) as `camera` sees the same surfaces from
// another pose: `moved` is that pose in the optical frame of the image's own. Each valid pixel's
// point is moved and projected to the nearest pixel, the nearest surface kept where several
// land (as cv::rgbd::registerDepth and depth_image_proc's register do); pixels nothing lands on
// are 0. Throws std::invalid_argument for another type or a size that is not the camera's.
cv::Mat depthSeenFrom(const cv::Mat& depth_m, const Camera& camera,
                      const Eigen::Isometry3d& moved);

}  // namespace acvo
