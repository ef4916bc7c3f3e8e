// OdometryNodelet: set-up, subscriptions and one frame's path, from the synchroniser to
// publish() or reject() (odometry_nodelet.hpp says what the nodelet does).
#include "odometry_nodelet.hpp"

#include <pluginlib/class_list_macros.hpp>

namespace acvo_ros {

void OdometryNodelet::onInit() {
  nh_ = getNodeHandle();
  pnh_ = getPrivateNodeHandle();
  loadSettings();

  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odom", 10);
  cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("cloud", 2);
  // Latched: the keyframe changes seldom, a late subscriber still gets the current one.
  keyframe_cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("keyframe_cloud", 1, true);
  info_pub_ = nh_.advertise<acvo::OdometryInfo>("odom_info", 10);
  reset_srv_ = nh_.advertiseService("reset_odom", &OdometryNodelet::onReset, this);
  reset_to_pose_srv_ =
      nh_.advertiseService("reset_odom_to_pose", &OdometryNodelet::onResetToPose, this);
  pause_srv_ = nh_.advertiseService("pause_odom", &OdometryNodelet::onPause, this);
  resume_srv_ = nh_.advertiseService("resume_odom", &OdometryNodelet::onResume, this);
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh_);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();

  // Start the server from the loaded values rather than from the .cfg defaults.
  reconfigure_ =
      std::make_unique<dynamic_reconfigure::Server<acvo::AcvoConfig>>(reconfigure_mutex_, pnh_);
  reconfigure_->updateConfig(toConfig(params_, settings_.lost_odom));
  reconfigure_->setCallback(
      [this](acvo::AcvoConfig& config, uint32_t level) { onReconfigure(config, level); });

  updater_ = std::make_unique<diagnostic_updater::Updater>(nh_, pnh_, getName());
  updater_->setHardwareID("acvo");
  updater_->add("odometry", this, &OdometryNodelet::diagnose);

  subscribe();
  last_sync_warning_ = last_.wall = ros::WallTime::now();
  watchdog_ = nh_.createWallTimer(ros::WallDuration(1.0), &OdometryNodelet::onWatchdog, this);
}

void OdometryNodelet::loadSettings() {
  XmlRpc::XmlRpcValue private_ns;
  ros::param::get(pnh_.getNamespace(), private_ns);
  // Each problem is logged once and kept for diagnostics.
  const auto report = [this](const std::vector<std::string>& problems, bool error) {
    for (const std::string& problem : problems) {
      if (error) {
        NODELET_ERROR("parameter problem: %s", problem.c_str());
      } else {
        NODELET_WARN("%s", problem.c_str());
      }
      parameter_problems_ += (parameter_problems_.empty() ? "" : "; ") + problem;
    }
  };
  report(loadNodeletSettings(private_ns, settings_), true);
  NODELET_INFO("nodelet settings: %s", describe(settings_).c_str());
  pending_base_pose_ = settings_.initial_pose;
  // dynamic_reconfigure's names and the parameters' keys without their section are told apart
  // below (sectionlessParameters): not unknown.
  std::vector<std::string> also_known = sectionlessNames();
  for (const auto& d : acvo::AcvoConfig::__getParamDescriptions__()) {
    also_known.push_back(d->name);
  }
  report(unknownParameters(private_ns, also_known), false);

  // odometry/threads: the config's (acvo.launch's threads argument when given) or the core's
  // default, -1: every core but one, which the camera driver in the same manager keeps.
  // Each value is checked by itself on top of the valid defaults: a bad one is rejected with its
  // reason, the rest are kept, so the set is always valid.
  report(applyRosParams(private_ns, params_), true);
  report(sectionlessParameters(private_ns, params_), false);
  odometry_ = std::make_unique<acvo::Odometry>(params_);
  NODELET_INFO("acvo parameters: %s", describeParams(params_).c_str());
}

void OdometryNodelet::subscribe() {
  const NodeletSettings& s = settings_;
  it_ = std::make_unique<image_transport::ImageTransport>(nh_);
  const image_transport::TransportHints rgb_hints("raw", ros::TransportHints(), pnh_,
                                                  "image_transport");
  const image_transport::TransportHints depth_hints("raw", ros::TransportHints(), pnh_,
                                                    "depth_image_transport");
  rgb_sub_.subscribe(*it_, "rgb/image", s.topic_queue_size, rgb_hints);
  depth_sub_.subscribe(*it_, "depth/image", s.topic_queue_size, depth_hints);
  info_sub_.subscribe(nh_, "rgb/camera_info", s.topic_queue_size);
  topics_ = {rgb_sub_.getTopic(), depth_sub_.getTopic(), info_sub_.getTopic()};
  rgb_sub_.registerCallback(
      boost::function<void(const ImageConstPtr&)>([this](const ImageConstPtr&) { ++count_.rgb; }));
  depth_sub_.registerCallback(boost::function<void(const ImageConstPtr&)>(
      [this](const ImageConstPtr&) { ++count_.depth; }));
  info_sub_.registerCallback(boost::function<void(const CameraInfoConstPtr&)>(
      [this](const CameraInfoConstPtr&) { ++count_.info; }));

  using namespace boost::placeholders;
  const auto callback = boost::bind(&OdometryNodelet::onFrame, this, _1, _2, _3);
  if (s.approx_sync) {
    approx_sync_ = std::make_unique<message_filters::Synchronizer<ApproxPolicy>>(
        ApproxPolicy(s.sync_queue_size), rgb_sub_, depth_sub_, info_sub_);
    if (s.approx_sync_max_interval > 0.0) {
      approx_sync_->setMaxIntervalDuration(ros::Duration(s.approx_sync_max_interval));
    }
    approx_sync_->setReset(true);  // clear the queues when a replayed clock jumps back
    approx_sync_->registerCallback(callback);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(s.sync_queue_size), rgb_sub_, depth_sub_, info_sub_);
    exact_sync_->setReset(true);
    exact_sync_->registerCallback(callback);
  }
  NODELET_INFO("subscribed to %s, %s, %s (%s sync; queues: %d per topic, %d in the synchroniser)",
               topics_.rgb.c_str(), topics_.depth.c_str(), topics_.info.c_str(),
               s.approx_sync ? "approximate" : "exact", s.topic_queue_size, s.sync_queue_size);
}

void OdometryNodelet::onFrame(const ImageConstPtr& rgb, const ImageConstPtr& depth,
                              const CameraInfoConstPtr& info) {
  const auto start = acvo::Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    processFrame(*rgb, *depth, *info);
  } catch (const std::exception& e) {
    // Whatever threw (a decoder, a TF lookup, the odometry), the frame goes the way of every
    // frame that is not processed: a named cause in odom_info and diagnostics.
    std_msgs::Header header = rgb->header;
    header.frame_id = stripSlash(rgb->header.frame_id);
    try {
      reject(header, std::string("unexpected error while processing the frame: ") + e.what(),
             acvo::msSince(start));
    } catch (const std::exception& again) {
      NODELET_ERROR_THROTTLE(5.0, "frame at %.6f skipped: %s (and reporting it failed: %s)",
                             rgb->header.stamp.toSec(), e.what(), again.what());
    }
  }
}

void OdometryNodelet::processFrame(const Image& rgb, const Image& depth, const Info& info) {
  const auto start = acvo::Clock::now();
  last_.wall = ros::WallTime::now();
  last_.synchronised = true;
  if (paused_) {
    ++count_.paused;
    return;
  }
  std_msgs::Header header = rgb.header;
  header.frame_id = stripSlash(rgb.header.frame_id);
  if (std::string why; !acceptStamp(header.stamp, &why)) {
    reject(header, why, acvo::msSince(start));
    return;
  }

  std::variant<acvo::Frame, Rejection> converted =
      frameFromMessages(rgb, depth, info, settings_.intrinsics, topics_);
  if (const Rejection* rejection = std::get_if<Rejection>(&converted)) {
    reject(header, rejection->why, acvo::msSince(start));
    return;
  }
  const acvo::Frame& frame = std::get<acvo::Frame>(converted);
  checkCamera(frame, header, depth, info);

  FrameTf tf = frameTf(header.stamp);
  if (pending_base_pose_ && tf.base_from_camera) {
    startAt(*pending_base_pose_, *tf.base_from_camera);
    tf.motion_guess.reset();
  }
  acvo::OdometryResult r = odometry_->process(frame, tf.motion_guess);
  logColourVerdict(r);
  if (!tf.base_from_camera && r.tracking != acvo::Tracking::kBadFrame) {
    r.message += std::string(r.message.empty() ? "" : "; ") + "not published: no transform from '" +
                 baseFrame() + "' to '" + camera_frame_ + "' yet";
  }
  noteResult(r);
  if (r.tracking == acvo::Tracking::kBadFrame) {
    // The conversion checks what the odometry checks: this is a safety net.
    reject(header, r.message, acvo::msSince(start));
    return;
  }
  ++count_.frames;
  stamps_.processed(header.stamp.toSec());
  const ContinuousOdom::Pose pose =
      continuous_.update(r, tf.motion_guess, header.stamp.toSec(), params_.odometry);
  if (r.tracking == acvo::Tracking::kLost) countLoss(r, tf.motion_guess.has_value());
  publish(r, pose, header, tf);
  InfoExtras extras;
  extras.guess_from_tf = tf.motion_guess.has_value() && r.tracking != acvo::Tracking::kFirstFrame;
  // On the ROS clock, as the stamps are: sim time when a bag is played with --clock.
  extras.ms_latency = (ros::Time::now() - header.stamp).toSec() * 1000.0;
  extras.ms_total = acvo::msSince(start);
  extras.lost_count = count_.lost;
  publishInfo(r, header, extras);
}

void OdometryNodelet::checkCamera(const acvo::Frame& frame, const std_msgs::Header& header,
                                  const Image& depth, const Info& info) {
  if (frame.order == acvo::ColorOrder::kGray) {
    NODELET_WARN_ONCE("%s is mono8: points get intensity and gradient labels but no colour",
                      topics_.rgb.c_str());
  }
  if (const std::string warning = unrectifiedWarning(info, settings_.intrinsics, topics_);
      !warning.empty()) {
    NODELET_WARN_ONCE("%s", warning.c_str());
  }
  noteCamera(frame.camera, info);
  const std::string depth_frame = stripSlash(depth.header.frame_id);
  if (!frame_ids_warned_ && depth_frame != header.frame_id) {
    frame_ids_warned_ = true;
    NODELET_WARN(
        "the depth image's frame_id '%s' differs from the colour image's '%s': the depth is "
        "taken as registered to the colour camera (pixel for pixel, in '%s'). Right for TUM "
        "bags, whose registered depth keeps the depth sensor's name, and for drivers' "
        "depth_registered topics; wrong for a raw depth image (use the registered one)",
        depth_frame.c_str(), header.frame_id.c_str(), header.frame_id.c_str());
  }
  if (header.frame_id != camera_frame_) {
    camera_frame_ = header.frame_id;
    odometry_->newCamera();  // the colour check looks again
    base_from_camera_.reset();
    base_waited_ = false;
  }
}

void OdometryNodelet::countLoss(const acvo::OdometryResult& r, bool guessed) {
  ++count_.lost;
  NODELET_WARN_THROTTLE(2.0, "tracking lost (%s): %s, %s (%u lost so far)", r.message.c_str(),
                        guessed ? "the pose follows the motion guess" : "holding the last pose",
                        r.new_keyframe ? "the reference restarts from this frame"
                                       : "the next frame is registered to the last good one",
                        count_.lost);
}

void OdometryNodelet::noteResult(const acvo::OdometryResult& r) {
  last_.tracking = r.tracking;
  last_.message = r.message;
  last_.depth_delay = r.depth_delay;
  last_.depth_synced = r.depth_synced || r.depth_retimed;
  last_.dense_weight =
      r.solver.coarse_to_fine ? r.solver.coarse_to_fine->dense_weight : std::nan("");
  if (last_.depth_synced && !depth_sync_told_) {
    depth_sync_told_ = true;
    NODELET_INFO("colour and depth stamps differ (%.1f ms on this frame): each frame's depth is "
                 "moved to its colour's time by the camera's motion (odometry/sync_depth)",
                 1e3 * r.depth_delay);
  }
}

bool OdometryNodelet::acceptStamp(const ros::Time& stamp, std::string* why) {
  const double last = stamps_.last();
  switch (stamps_.check(stamp.toSec(), settings_.max_time_gap, kTimeJumpBack)) {
    case StampVerdict::kAccept:
      return true;
    case StampVerdict::kGap:
      NODELET_WARN_THROTTLE(5.0,
                            "%.3f s between frames (max_time_gap %.3f): continuing, the motion "
                            "guess may be poor",
                            stamp.toSec() - last, settings_.max_time_gap);
      return true;
    case StampVerdict::kDrop: {
      char text[160];
      std::snprintf(text, sizeof text,
                    "stamp %.6f is not after the last processed frame's, %.6f (a repeated or "
                    "reordered frame)",
                    stamp.toSec(), last);
      *why = text;
      return false;
    }
    case StampVerdict::kRestart:
      if (ros::Time::isSimTime()) {
        // A bag played again (rosbag play --loop --clock): the run starts over, from the start
        // pose as the first time.
        NODELET_WARN("time jumped back by %.3f s on the simulated clock (bag restarted?): "
                     "odometry restarts at %s",
                     last - stamp.toSec(), settings_.initial_pose ? "initial_pose" : "the origin");
        restart(Eigen::Isometry3d::Identity());
        pending_base_pose_ = settings_.initial_pose;
      } else {
        // A live camera (a driver restart, a clock step): the robot has not gone back to the
        // origin. Keep the pose, restart the reference from this frame.
        NODELET_WARN("time jumped back by %.3f s on the wall clock (driver restarted, clock "
                     "stepped?): the pose is kept, tracking restarts from this frame",
                     last - stamp.toSec());
        odometry_->reset(odometry_->pose(), odometry_->poseCovariance());
        published_keyframe_.reset();
      }
      stamps_.clear();
      return true;
  }
  return false;
}

void OdometryNodelet::noteCamera(const acvo::Camera& camera, const Info& info) {
  const auto same = [](const acvo::Camera& a, const acvo::Camera& b) {
    return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && a.width == b.width &&
           a.height == b.height;
  };
  const bool nominal = nominalCameraInfo(info, settings_.intrinsics);
  if (camera_told_ && same(*camera_told_, camera) && nominal == camera_told_nominal_) return;
  camera_told_ = camera;
  camera_told_nominal_ = nominal;
  camera_text_ = describeCamera(camera, settings_.intrinsics, topics_);
  // Throttled: a topic whose camera_info alternates between two cameras changes on every frame.
  if (nominal) {
    camera_text_ += "; nominal, not a calibration";
    if (info.binning_x > 1 || info.binning_y > 1 || info.roi.width > 0) {
      camera_text_ += " (camera_info's own, before binning and its region of interest, at its " +
                      std::to_string(info.width) + "x" + std::to_string(info.height) + ")";
    }
    NODELET_WARN_THROTTLE(kCameraNote,
        "camera intrinsics: %s. Equal focal lengths, the principal point at the image's centre "
        "and no distortion are a driver's defaults, not a calibration: exact for a simulated "
        "camera, but a real one's may be a few percent off, and acvo, which registers the depth's "
        "geometry, carries that in full in its translation. Calibrate the camera "
        "(camera_calibration) or set ~fx, ~fy, ~cx, ~cy; for a TUM bag, ~camera fr1, fr2 or fr3",
        camera_text_.c_str());
  } else {
    NODELET_INFO_THROTTLE(kCameraNote, "camera intrinsics: %s", camera_text_.c_str());
  }
}

void OdometryNodelet::logColourVerdict(const acvo::OdometryResult& r) {
  if (!r.colour_verdict_now) return;
  const std::string text = odometry_->describeColour();
  if (odometry_->colourCheck().verdict().state == acvo::ColourDepthCheck::State::kUnregistered) {
    NODELET_WARN("%s", text.c_str());
  } else {
    NODELET_INFO("%s", text.c_str());
  }
}

void OdometryNodelet::reject(const std_msgs::Header& header, const std::string& why,
                             double ms_total) {
  ++count_.rejected;
  last_.tracking = acvo::Tracking::kBadFrame;
  last_.message = why;
  if (skip_warnings_.allow(why, ros::WallTime::now().toSec())) {
    NODELET_WARN("frame skipped: %s", why.c_str());
  }
  acvo::OdometryResult r;
  r.tracking = acvo::Tracking::kBadFrame;
  r.message = why;
  InfoExtras extras;
  extras.ms_total = ms_total;
  extras.ms_latency = (ros::Time::now() - header.stamp).toSec() * 1000.0;
  extras.lost_count = count_.lost;
  publishInfo(r, header, extras);
}

}  // namespace acvo_ros

PLUGINLIB_EXPORT_CLASS(acvo_ros::OdometryNodelet, nodelet::Nodelet)
