// OdometryNodelet: restarts, its services (reset_odom, reset_odom_to_pose, pause_odom,
// resume_odom), dynamic_reconfigure, the watchdog and diagnostics.
#include "odometry_nodelet.hpp"

namespace acvo_ros {

void OdometryNodelet::restart(const Eigen::Isometry3d& camera_pose) {
  odometry_->reset(camera_pose);
  continuous_.reset();
  published_keyframe_.reset();
}

void OdometryNodelet::startAt(const Eigen::Isometry3d& base_pose,
                              const Eigen::Isometry3d& base_from_camera) {
  // The engine holds the camera pose in the first camera's frame: undo the conjugation.
  restart(conjugate(base_from_camera.inverse(), base_pose));
  pending_base_pose_.reset();
}

bool OdometryNodelet::onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    restart(Eigen::Isometry3d::Identity());
    pending_base_pose_.reset();
    NODELET_INFO("odometry reset to identity");
    return true;
  } catch (const std::exception& e) {
    NODELET_ERROR("reset_odom failed: %s", e.what());
    return false;
  }
}

bool OdometryNodelet::onResetToPose(acvo::ResetToPose::Request& req,
                                    acvo::ResetToPose::Response& res) {
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string problem;
    const Eigen::Isometry3d base_pose = fromPoseMsg(req.pose, &problem);
    if (!problem.empty()) {
      res.success = false;
      res.message = problem;
      return true;
    }
    const bool camera_known = !camera_frame_.empty();
    const std::optional<Eigen::Isometry3d> base_from_camera =
        camera_known ? baseFromCamera() : std::nullopt;
    if (base_from_camera) {
      startAt(base_pose, *base_from_camera);
      res.message = "odometry restarts from the given pose";
    } else {
      // Before the first frame, or before the camera-to-base transform: the next frame whose
      // transform is known starts there (the frames meanwhile are not published anyway).
      restart(Eigen::Isometry3d::Identity());
      pending_base_pose_ = base_pose;
      res.message = std::string("odometry starts from the given pose at the first frame ") +
                    (camera_known ? "whose camera-to-base transform ('" + baseFrame() + "' to '" +
                                        camera_frame_ + "') is known"
                                  : "(none received yet)");
    }
    res.success = true;
    NODELET_INFO("reset_odom_to_pose: %s", res.message.c_str());
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
  }
  return true;
}

bool OdometryNodelet::onPause(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (paused_) {
    NODELET_WARN("pause_odom: already paused");
  } else {
    paused_ = true;
    NODELET_INFO("odometry paused: frames are dropped until resume_odom");
  }
  return true;
}

bool OdometryNodelet::onResume(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!paused_) {
    NODELET_WARN("resume_odom: not paused");
  } else {
    paused_ = false;
    NODELET_INFO(
        "odometry resumed: the next frame is registered to the last tracked one "
        "(%lu frames dropped while paused)",
        static_cast<unsigned long>(count_.paused));
  }
  return true;
}

void OdometryNodelet::onReconfigure(acvo::AcvoConfig& config, uint32_t /*level*/) {
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    fromString(config.lost_odom, settings_.lost_odom);
    const acvo::Params next = fromConfig(config, params_);
    const std::string invalid = acvo::validate(next);
    if (!invalid.empty()) {
      NODELET_ERROR("dynamic_reconfigure: %s: keeping the previous parameters", invalid.c_str());
      // The server publishes what the callback leaves in `config`: show the values in use.
      config = toConfig(params_, settings_.lost_odom);
      return;
    }
    if (describeParams(next) == describeParams(params_)) return;
    const Eigen::Isometry3d pose = odometry_->pose();
    const acvo::Matrix6d covariance = odometry_->poseCovariance();
    const acvo::ColourDepthCheck check = odometry_->colourCheck();  // the camera is the same
    params_ = next;
    odometry_ = std::make_unique<acvo::Odometry>(params_);
    odometry_->reset(pose, covariance);
    odometry_->takeColourCheck(check);
    published_keyframe_.reset();
    NODELET_INFO("parameters changed, tracking restarts from the current pose: %s",
                 describeParams(params_).c_str());
  } catch (const std::exception& e) {
    NODELET_ERROR("dynamic_reconfigure: %s: keeping the previous parameters", e.what());
    config = toConfig(params_, settings_.lost_odom);
  }
}

void OdometryNodelet::onWatchdog(const ros::WallTimerEvent&) {
  try {
    updater_->force_update();
    const ros::WallTime now = ros::WallTime::now();
    std::lock_guard<std::mutex> lock(mutex_);
    const double silent = (now - last_.wall).toSec();
    if (silent > kNoSyncWarning && (now - last_sync_warning_).toSec() > kNoSyncWarning) {
      last_sync_warning_ = now;
      NODELET_WARN(
          "no synchronised frame for %.0f s on %s, %s, %s (messages received so far: %lu, %lu, "
          "%lu)",
          silent, topics_.rgb.c_str(), topics_.depth.c_str(), topics_.info.c_str(),
          static_cast<unsigned long>(count_.rgb.load()),
          static_cast<unsigned long>(count_.depth.load()),
          static_cast<unsigned long>(count_.info.load()));
    }
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(10.0, "watchdog: %s", e.what());
  }
}

void OdometryNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  const double silent = (ros::WallTime::now() - last_.wall).toSec();
  const DiagnosticSummary summary =
      summarise(last_.synchronised, silent, settings_.no_data_timeout, last_.tracking, paused_);
  stat.summary(summary.level, summary.message);
  stat.add("seconds since last frame", silent);
  stat.add("frames processed", count_.frames);
  stat.add("frames lost", count_.lost);
  stat.add("frames rejected", count_.rejected);
  stat.add("frames dropped while paused", count_.paused);
  stat.add("last tracking", acvo::toString(last_.tracking));
  stat.add("last message", last_.message);
  stat.add("camera intrinsics", camera_text_);
  stat.add("last ms total", last_.ms_total);
  stat.add("last ms latency", last_.ms_latency);
  stat.add("colour/depth registration",
           acvo::toString(odometry_->colourCheck().verdict().state) +
               (odometry_->colourResampling() ? " (colour resampled to the depth camera)" : ""));
  const char* moved = last_.depth_synced ? ", depth moved to the colour's time" : "";
  stat.addf("colour stamp - depth stamp (ms)", "%.2f%s", 1e3 * last_.depth_delay, moved);
  stat.add("dense depth term weight", denseWeightText(last_.dense_weight, last_.depth_delay));
  stat.add("parameter problems",
           parameter_problems_.empty() ? std::string("none") : parameter_problems_);
  stat.add("messages received (rgb, depth, info)", std::to_string(count_.rgb.load()) + ", " +
                                                       std::to_string(count_.depth.load()) + ", " +
                                                       std::to_string(count_.info.load()));
}

}  // namespace acvo_ros
