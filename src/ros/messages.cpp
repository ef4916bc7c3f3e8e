#include "messages.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <diagnostic_msgs/KeyValue.h>
#include <tf2_eigen/tf2_eigen.h>

#include "conversions.hpp"

namespace acvo_ros {

nav_msgs::Odometry toOdometryMsg(const acvo::OdometryResult& result,
                                 const Eigen::Isometry3d& base_from_camera,
                                 const std_msgs::Header& header, const std::string& child) {
  const Eigen::Matrix3d rot = base_from_camera.rotation();
  nav_msgs::Odometry odom;
  odom.header = header;
  odom.child_frame_id = child;
  odom.pose.pose = toPoseMsg(conjugate(base_from_camera, result.pose));
  const auto pose_cov = toArray(
      acvo::rotateCovariance(toRosOrder(acvo::sanitiseCovariance(result.pose_covariance)), rot));
  std::copy(pose_cov.begin(), pose_cov.end(), odom.pose.covariance.begin());

  Covariance6 twist_cov = lostCovariance();
  const bool registered =
      result.tracking == acvo::Tracking::kOk || result.tracking == acvo::Tracking::kHard;
  const double dt = result.interval;
  if (registered && dt > 0.0) {
    const Twist twist = twistOf(conjugate(base_from_camera, result.motion), dt);
    tf2::toMsg(twist.linear, odom.twist.twist.linear);
    tf2::toMsg(twist.angular, odom.twist.twist.angular);
    twist_cov = acvo::rotateCovariance(
                    toRosOrder(acvo::sanitiseCovariance(result.motion_covariance)), rot) /
                (dt * dt);
  }
  const auto twist_arr = toArray(twist_cov);
  std::copy(twist_arr.begin(), twist_arr.end(), odom.twist.covariance.begin());
  return odom;
}

nav_msgs::Odometry nullOdometryMsg(const std_msgs::Header& header, const std::string& child) {
  nav_msgs::Odometry odom;
  odom.header = header;
  odom.child_frame_id = child;
  odom.pose.pose.orientation.w = 0.0;  // geometry_msgs defaults to 0 already: said for the reader
  for (int d = 0; d < 6; ++d) {
    odom.pose.covariance[7 * d] = kLostVariance;
    odom.twist.covariance[7 * d] = kLostVariance;
  }
  return odom;
}

acvo::OdometryInfo toInfoMsg(const acvo::OdometryResult& result, const std_msgs::Header& header,
                             const InfoExtras& extras) {
  acvo::OdometryInfo info;
  info.header = header;
  info.lost = result.tracking == acvo::Tracking::kLost;
  info.tracking = acvo::toString(result.tracking);
  info.status = acvo::toString(result.solver.status);
  info.iterations = result.solver.iterations;
  info.ell = result.solver.ell;
  info.fixed_points = static_cast<std::uint32_t>(result.fixed_points);
  info.moving_points = static_cast<std::uint32_t>(result.moving_points);
  info.nnz = result.solver.nnz;
  for (const auto& [name, value] : acvo::engineFigures(result.solver)) {
    diagnostic_msgs::KeyValue figure;
    figure.key = name;
    std::ostringstream text;
    text << std::setprecision(9) << value;
    figure.value = text.str();
    info.engine_figures.push_back(figure);
  }
  info.matched_fraction = result.solver.matched_fraction;
  info.frame_index = result.frame_index;
  info.keyframe_index = result.keyframe_index;
  info.new_keyframe = result.new_keyframe;
  info.fell_back_to_previous = result.fell_back_to_previous;
  info.interval = result.interval;
  info.guess_from_tf = extras.guess_from_tf;
  info.second_start = result.second_start;
  info.second_start_kept = result.second_start_kept;
  info.ms_cloud = result.ms_cloud;
  info.ms_registration = result.ms_registration;
  info.ms_total = extras.ms_total;
  info.ms_latency = extras.ms_latency;
  info.lost_count = extras.lost_count;
  info.message = result.message;
  return info;
}

DiagnosticSummary summarise(bool synchronised, double seconds_since_frame, double no_data_timeout,
                            acvo::Tracking last, bool paused) {
  using diagnostic_msgs::DiagnosticStatus;
  if (paused) return {DiagnosticStatus::WARN, "paused"};
  if (!synchronised || seconds_since_frame > no_data_timeout) {
    return {DiagnosticStatus::ERROR, "no data"};
  }
  switch (last) {
    case acvo::Tracking::kOk:
    case acvo::Tracking::kFirstFrame:
      return {DiagnosticStatus::OK, "tracking"};
    case acvo::Tracking::kHard:
      return {DiagnosticStatus::WARN, "hard to track"};
    case acvo::Tracking::kLost:
      return {DiagnosticStatus::ERROR, "lost"};
    case acvo::Tracking::kBadFrame:
      break;
  }
  return {DiagnosticStatus::ERROR, "bad input"};
}

std::string denseWeightText(double weight, double depth_delay) {
  if (std::isnan(weight)) return "not in use";
  if (weight > 0.0) {
    char text[16];
    std::snprintf(text, sizeof text, "%.2f", weight);
    return text;
  }
  if (depth_delay != 0.0) return "0 (off: the depth's stamp is not the colour's)";
  return "0 (off: the depth's noise is shared between neighbouring pixels, as a structured-light "
         "camera's)";
}

}  // namespace acvo_ros
