// The depth moved to the colour's instant (depth_timing.hpp).
#include "acvo/odometry/depth_timing.hpp"

#include <algorithm>
#include <cmath>

#include "acvo/cloud/depth.hpp"
#include "acvo/math/se3.hpp"

namespace acvo {

double largestPixelShift(const Eigen::Isometry3d& moved, const Camera& c, double nearest) {
  const double corner2 =
      0.25 * ((c.width / c.fx) * (c.width / c.fx) + (c.height / c.fy) * (c.height / c.fy));
  const double angle = logSO3(moved.linear()).norm();
  return std::max(std::abs(c.fx), std::abs(c.fy)) *
         (angle * (1.0 + corner2) + moved.translation().norm() / std::max(nearest, kNearestShift));
}

std::optional<cv::Mat> depthMovedBy(const Frame& frame, const Eigen::Isometry3d& moved,
                                    double nearest) {
  if (largestPixelShift(moved, frame.camera, nearest) < kSyncMinShift) return std::nullopt;
  return depthSeenFrom(frame.depth, frame.camera, moved);
}

std::optional<LabelledCloud> retimedCloud(const LabelledCloud& cloud, const Frame& frame,
                                          const Eigen::Isometry3d& before,
                                          const Eigen::Isometry3d& now,
                                          const SelectionParams& selection) {
  if (largestPixelShift(before.inverse() * now, frame.camera, selection.min_depth) <
      kSyncMinShift) {
    return std::nullopt;
  }
  // The pixels stay those selected: the colour image has not changed, only where the depth
  // puts their points.
  return withDepth(cloud, depthSeenFrom(frame.depth, frame.camera, now), selection);
}

}  // namespace acvo
