// The nodelet's outgoing messages built from an odometry result: nav_msgs/Odometry for a base
// frame rigidly attached to the camera, the per-frame OdometryInfo, and the diagnostic summary.
// Values in, messages out; publishing stays in the nodelet.
#pragma once

#include <cstdint>
#include <string>

#include <nav_msgs/Odometry.h>
#include <std_msgs/Header.h>
#include <Eigen/Geometry>

#include "acvo/OdometryInfo.h"
#include "acvo/odometry/odometry.hpp"
#include "covariance.hpp"

namespace acvo_ros {

// `header`: stamp and odometry frame; `child`: the base frame. The pose is the camera pose
// conjugated by `base_from_camera`; its covariance (result.pose_covariance, first camera's
// axes) is put in ROS order and rotated into the base axes. The twist is the conjugated
// relative motion over result.interval, in the base frame, with covariance
// motion_covariance / interval^2; it is zero with lostCovariance() for a first frame, a lost
// frame or an interval <= 0 (velocity unknown).
nav_msgs::Odometry toOdometryMsg(const acvo::OdometryResult& result,
                                 const Eigen::Isometry3d& base_from_camera,
                                 const std_msgs::Header& header, const std::string& child);

// rtabmap's "null" odometry for a lost frame (lost_odom null): header and child, a zero pose
// with an all-zero quaternion, a zero twist, kLostVariance on both covariance diagonals.
nav_msgs::Odometry nullOdometryMsg(const std_msgs::Header& header, const std::string& child);

// What the nodelet adds to the result in odom_info.
struct InfoExtras {
  double ms_total = 0.0;    // the whole callback (ms)
  double ms_latency = 0.0;  // image stamp to publishing (ms, ROS clock)
  std::uint32_t lost_count = 0;
  bool guess_from_tf = false;
};
acvo::OdometryInfo toInfoMsg(const acvo::OdometryResult& result, const std_msgs::Header& header,
                             const InfoExtras& extras);

// What diagnostics say: WARN "paused" while paused (pause_odom); "no data" (ERROR) when nothing
// was synchronised yet or for longer than `no_data_timeout` s; otherwise from the last frame:
// OK "tracking" (ok, first frame), WARN "hard to track", ERROR "lost", ERROR "bad input".
struct DiagnosticSummary {
  std::uint8_t level = 0;  // diagnostic_msgs::DiagnosticStatus level
  std::string message;
};
DiagnosticSummary summarise(bool synchronised, double seconds_since_frame, double no_data_timeout,
                            acvo::Tracking last, bool paused = false);

// What diagnostics say of the dense depth term (SolverResult::dense_weight) on the last frame:
// its weight, or why it is off: "not in use" (NaN: another engine, or turned off), the depth's
// stamp not the colour's (depth_delay s), or its noise shared between neighbouring pixels.
std::string denseWeightText(double weight, double depth_delay);

}  // namespace acvo_ros
