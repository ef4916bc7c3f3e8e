// Colour and depth taken at different instants (free-running streams: a Kinect v1's, a
// RealSense's; Frame::depth_stamp): the depth is moved to the colour's time by the camera's
// motion over the delay, so that each point's colour and position are of one instant
// (OdometryParams::sync_depth). The odometry moves it by the last frame-to-frame motion before
// the cloud is built, and again by the frame's own motion, as the registration's coarse levels
// find it, before the finest level.
#pragma once

#include <optional>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"
#include "acvo/cloud/frame.hpp"
#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/params.hpp"

namespace acvo {

// A depth image moved by less than this many pixels is left as it is (TUM fr3's streams are
// synchronised to tens of microseconds).
inline constexpr double kSyncMinShift = 0.1;

// An upper bound of the image motion `moved` causes, in pixels: its rotation's at the image's
// corner and its translation's at `nearest` metres (at least kNearestShift).
inline constexpr double kNearestShift = 0.1;  // m
double largestPixelShift(const Eigen::Isometry3d& moved, const Camera& c, double nearest);

// The frame's depth as the camera would have seen it after `moved` (T: later camera -> the
// depth's camera), where that shifts a pixel by kSyncMinShift or more (`nearest`: the nearest
// depth used); nullopt otherwise.
std::optional<cv::Mat> depthMovedBy(const Frame& frame, const Eigen::Isometry3d& moved,
                                    double nearest);

// The cloud of the same pixels with their points from the frame's depth moved by `now` instead
// of `before` (what the cloud was built with), where the two differ by kSyncMinShift pixels or
// more; nullopt otherwise.
std::optional<LabelledCloud> retimedCloud(const LabelledCloud& cloud, const Frame& frame,
                                          const Eigen::Isometry3d& before,
                                          const Eigen::Isometry3d& now,
                                          const SelectionParams& selection);

}  // namespace acvo
