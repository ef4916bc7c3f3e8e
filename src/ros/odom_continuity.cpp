#include "odom_continuity.hpp"

#include "acvo/odometry/covariance.hpp"
#include "acvo/math/se3.hpp"

namespace acvo_ros {

ContinuousOdom::Pose ContinuousOdom::update(const acvo::OdometryResult& r,
                                            const std::optional<Eigen::Isometry3d>& guess,
                                            double stamp, const acvo::OdometryParams& params) {
  const Eigen::Isometry3d dead_reckoned =
      reference_ * (guess ? *guess : Eigen::Isometry3d::Identity());
  const bool tracked = r.tracking == acvo::Tracking::kOk || r.tracking == acvo::Tracking::kHard;
  if (r.tracking == acvo::Tracking::kFirstFrame && published_) {
    // The odometry restarted from its own pose (new parameters, a live clock stepping back),
    // which is the held one while lost: go on from what was published, dead-reckoned or not.
    correction_ = *published_ * r.pose.inverse();
  }
  const bool continuous_by_correction =
      r.tracking == acvo::Tracking::kFirstFrame || (tracked && !lost_) ||
      (tracked && lost_reference_ && r.keyframe_index == *lost_reference_);
  Pose out;
  if (continuous_by_correction) {
    out.pose = acvo::normalized(correction_ * r.pose);
  } else {
    // Lost, or registered again to a reference from before the loss: from the dead-reckoned
    // pose on, whatever the odometry's own pose jumped to.
    out.pose = acvo::normalized(dead_reckoned);
    // Only where the odometry's later poses will build on this frame: a recovery, or a lost
    // frame that becomes the reference (frames registered to it then follow on).
    if (tracked || r.new_keyframe) correction_ = out.pose * r.pose.inverse();
    if (tracked) carried_ += acvo::lostGrowth(stamp - reference_stamp_, params);
  }
  const acvo::Matrix6d ad = acvo::adjointSE3(correction_);
  out.covariance = ad * r.pose_covariance * ad.transpose() + carried_;

  if (r.tracking == acvo::Tracking::kLost) {
    lost_ = true;
    if (r.new_keyframe) {
      lost_reference_ = r.frame_index;
      reference_ = out.pose;
      reference_stamp_ = stamp;
    }
  } else {
    lost_ = false;
    lost_reference_.reset();
    reference_ = out.pose;
    reference_stamp_ = stamp;
  }
  published_ = out.pose;
  return out;
}

void ContinuousOdom::reset() {
  *this = ContinuousOdom();
}

}  // namespace acvo_ros
