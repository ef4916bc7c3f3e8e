// The pose the nodelet publishes in the odom frame. REP 105 asks the odom frame to evolve
// continuously: no jump when tracking is lost, none when it comes back. The odometry holds its
// pose while lost and, when a frame is registered again to a reference from before the loss,
// its pose jumps by the motion unseen meanwhile. This keeps a correction between the two:
//  - while lost, the published pose dead-reckons from the last tracked frame on the motion
//    guess (wheel odometry through TF), or stays where it was when there is none;
//  - on recovery, publishing continues from there: the correction absorbs the jump, and the
//    motion the camera measures from then on is applied to the published pose;
//  - the covariance grows while lost (the odometry's lostGrowth) and keeps what a bridged
//    blackout added, since the published pose did not take the registration's word for it;
//  - a restart that keeps the pose (new parameters, a live clock stepping back: the odometry is
//    reset to its own pose, which is the held one while lost) starts where the last published
//    pose was, dead-reckoned or not: its first frame takes that pose, not the odometry's.
// Without a guess, the motion during a blackout is therefore missing from odom (it drifts by
// it, as REP 105 allows), instead of arriving as a jump.
// Poses here are camera poses in the odometry's frame (acvo::OdometryResult::pose).
#pragma once

#include <cstdint>
#include <optional>

#include <Eigen/Geometry>

#include "acvo/odometry/odometry.hpp"

namespace acvo_ros {

class ContinuousOdom {
 public:
  struct Pose {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    acvo::Matrix6d covariance = acvo::originCovariance();
  };

  // The pose to publish for a frame the odometry processed (not a bad frame). `guess`: the
  // motion guess given to the odometry for this frame (T: current -> last tracked camera), if
  // any; `stamp`: the frame's (s).
  Pose update(const acvo::OdometryResult& r, const std::optional<Eigen::Isometry3d>& guess,
              double stamp, const acvo::OdometryParams& params);

  // The odometry was reset to a pose given by the user (or a restarted bag): its poses are
  // published as they are from the next frame on. Not for a restart that keeps the pose (new
  // parameters, a live clock stepping back): without a reset, a first frame is published at the
  // last published pose and publishing continues from there.
  void reset();

  bool lost() const { return lost_; }

 private:
  Eigen::Isometry3d correction_ = Eigen::Isometry3d::Identity();  // published = this * odometry's
  Eigen::Isometry3d reference_ = Eigen::Isometry3d::Identity();   // published pose of the odometry's
  double reference_stamp_ = 0.0;                                  // last tracked frame, and its stamp
  // A lost frame the odometry took as its reference: frames registered to it are continuous
  // through the correction set when it was published.
  std::optional<std::uint64_t> lost_reference_;
  bool lost_ = false;
  acvo::Matrix6d carried_ = acvo::Matrix6d::Zero();  // what bridged blackouts added
  // The pose last published (none since the start or a reset): where a first frame without a
  // reset goes on from.
  std::optional<Eigen::Isometry3d> published_;
};

}  // namespace acvo_ros
