// The ROS face of acvo: synchronised colour + depth + camera info in, odometry, TF, the
// labelled cloud, a per-frame report and diagnostics out. The nodelet converts messages, calls
// acvo::Odometry and publishes; the method lives in the core library.
//
// One frame's path: onFrame (lock) -> processFrame: stamp rules, conversion, the camera-to-base
// transform, the motion guess from TF, the odometry, then publish() and publishInfo(). A frame
// that is not processed (its stamp, its messages, the odometry's own checks, an exception) goes
// through reject(), the one place: a named cause in odom_info, the log and diagnostics. Only
// frames dropped on request (pause_odom) are not reported one by one.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <boost/bind/bind.hpp>
#include <boost/thread/recursive_mutex.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "acvo/AcvoConfig.h"
#include "acvo/ResetToPose.h"
#include "acvo/cloud/colour_depth_check.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/timing.hpp"
#include "cause_throttle.hpp"
#include "conversions.hpp"
#include "covariance.hpp"
#include "messages.hpp"
#include "nodelet_settings.hpp"
#include "odom_continuity.hpp"
#include "ros_params.hpp"
#include "stamp_check.hpp"

namespace acvo_ros {

using sensor_msgs::CameraInfoConstPtr;
using sensor_msgs::ImageConstPtr;

namespace {
// A stamp earlier than the last one by more than this (s) is a restarted stream, not a
// reordering (StampGuard also tells a shorter jump back from a reordering).
constexpr double kTimeJumpBack = 1.0;
// Warn when the synchroniser has produced nothing for this long (wall seconds).
constexpr double kNoSyncWarning = 5.0;
// Period of the warning about each cause of a skipped frame (s).
constexpr double kSkipWarning = 5.0;
// Period of the warning about a motion guess that could not be looked up (s).
constexpr double kGuessWarning = 10.0;
// Period of the note on the camera intrinsics in use, when they change (s).
constexpr double kCameraNote = 5.0;

}  // namespace

class OdometryNodelet : public nodelet::Nodelet {
 private:
  using Image = sensor_msgs::Image;
  using Info = sensor_msgs::CameraInfo;
  using ExactPolicy = message_filters::sync_policies::ExactTime<Image, Image, Info>;
  using ApproxPolicy = message_filters::sync_policies::ApproximateTime<Image, Image, Info>;

  // What came out of TF for one frame.
  struct FrameTf {
    std::optional<Eigen::Isometry3d> base_from_camera;
    std::optional<Eigen::Isometry3d> motion_guess;     // camera: this frame -> last tracked one
    std::optional<Eigen::Isometry3d> guess_from_base;  // the base in guess_frame_id, now
  };

  void onInit() override;
  void loadSettings();
  void subscribe();

  void onFrame(const ImageConstPtr& rgb, const ImageConstPtr& depth,
               const CameraInfoConstPtr& info);
  void processFrame(const Image& rgb, const Image& depth, const Info& info);
  // Applies the stamp rules (stamp_check.hpp); false with the reason in *why for a frame to
  // drop.
  bool acceptStamp(const ros::Time& stamp, std::string* why);
  void reject(const std_msgs::Header& header, const std::string& why, double ms_total);
  // The warnings a frame's camera gets once (mono8, unrectified, depth in another frame), and a
  // new camera frame noted: the colour check looks again and the base transform is looked up.
  void checkCamera(const acvo::Frame& frame, const std_msgs::Header& header, const Image& depth,
                   const Info& info);
  // Logs the intrinsics in use when they are new: at the first frame and at a change.
  void noteCamera(const acvo::Camera& camera, const Info& info);
  // Keeps what diagnostics report of the last frame; says once that the depth is retimed.
  void noteResult(const acvo::OdometryResult& r);
  // Counts a lost frame and warns (throttled): what the pose does meanwhile, what comes next.
  void countLoss(const acvo::OdometryResult& r, bool guessed);
  // Logs the colour check's verdict when it comes (Odometry::colourCheck).
  void logColourVerdict(const acvo::OdometryResult& r);
  std::string baseFrame() const;
  bool baseIsCamera() const;
  std::optional<Eigen::Isometry3d> lookup(const std::string& target, const std::string& source,
                                          const ros::Time& stamp, double wait, std::string* error);
  std::optional<Eigen::Isometry3d> baseFromCamera();
  FrameTf frameTf(const ros::Time& stamp);
  void publish(const acvo::OdometryResult& r, const ContinuousOdom::Pose& pose,
               const std_msgs::Header& header, const FrameTf& tf);
  void publishInfo(const acvo::OdometryResult& r, const std_msgs::Header& header,
                   const InfoExtras& extras);
  void restart(const Eigen::Isometry3d& camera_pose);
  void startAt(const Eigen::Isometry3d& base_pose, const Eigen::Isometry3d& base_from_camera);

  bool onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool onResetToPose(acvo::ResetToPose::Request& req, acvo::ResetToPose::Response& res);
  bool onPause(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool onResume(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  void onReconfigure(acvo::AcvoConfig& config, uint32_t level);
  void onWatchdog(const ros::WallTimerEvent&);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  // Set in onInit; lost_odom also by dynamic_reconfigure.
  NodeletSettings settings_;
  // What loading the parameters found wrong ("; "-separated): logged once, and kept in
  // diagnostics for whoever looks later.
  std::string parameter_problems_;
  InputTopics topics_;

  ros::NodeHandle nh_, pnh_;
  std::unique_ptr<image_transport::ImageTransport> it_;
  image_transport::SubscriberFilter rgb_sub_, depth_sub_;
  message_filters::Subscriber<Info> info_sub_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproxPolicy>> approx_sync_;
  ros::Publisher odom_pub_, cloud_pub_, keyframe_cloud_pub_, info_pub_;
  ros::ServiceServer reset_srv_, reset_to_pose_srv_, pause_srv_, resume_srv_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<acvo::AcvoConfig>> reconfigure_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer watchdog_;

  // Counts, for odom_info, diagnostics and the no-data warning. The message counts are
  // incremented by the subscribers' callbacks, outside the mutex.
  struct Counters {
    std::uint64_t frames = 0;  // frames the odometry processed (not rejected)
    std::uint32_t lost = 0;
    std::uint64_t rejected = 0;  // frames that went through reject()
    std::uint64_t paused = 0;    // synchronised frames dropped while paused
    std::atomic<std::uint64_t> rgb{0}, depth{0}, info{0};
  };
  // What the last frame left, for diagnostics.
  struct LastFrame {
    bool synchronised = false;  // a frame came out of the synchroniser
    acvo::Tracking tracking = acvo::Tracking::kFirstFrame;
    std::string message;
    double ms_total = 0.0;
    double ms_latency = 0.0;
    double depth_delay = 0.0;   // s from the depth's stamp to the colour's
    bool depth_synced = false;  // the depth was moved to the colour's time
    // The dense depth term's weight (NaN: not in use).
    double dense_weight = std::nan("");
    ros::WallTime wall;  // last synchronised frame, good or bad
  };

  // State, guarded by mutex_. Every callback here (frames, services, reconfigure, the watchdog)
  // comes through getNodeHandle()/getPrivateNodeHandle(), whose queue a nodelet manager serves
  // one callback at a time: they never overlap today, and a frame that waits blocks all of them
  // (hence no per-frame TF wait). The mutex keeps the state safe should one move to the
  // multi-threaded handle.
  std::mutex mutex_;
  acvo::Params params_;
  std::unique_ptr<acvo::Odometry> odometry_;
  bool paused_ = false;
  std::string camera_frame_;                           // optical frame of the last image
  std::optional<Eigen::Isometry3d> base_from_camera_;  // looked up once per camera frame
  bool base_waited_ = false;  // waited once for base_from_camera_ (per camera frame)
  bool frame_ids_warned_ = false;
  bool depth_sync_told_ = false;  // said once that colour and depth stamps differ
  // The intrinsics last logged, and the line that said them (for diagnostics): logged at the
  // first frame and again whenever they change.
  std::optional<acvo::Camera> camera_told_;
  bool camera_told_nominal_ = false;
  std::string camera_text_ = "none yet";
  ContinuousOdom continuous_;  // the published pose (odom_continuity.hpp)
  // A base pose to start from (initial_pose, or reset_odom_to_pose before the camera-to-base
  // transform was known): applied at the first frame whose transform is known.
  std::optional<Eigen::Isometry3d> pending_base_pose_;
  bool guess_found_ = true;  // the last lookup of guess_frame_id succeeded: worth waiting for
  StampGuard stamps_;        // the stamps processed so far
  std::optional<std::uint64_t> published_keyframe_;  // last keyframe sent on keyframe_cloud
  Counters count_;
  LastFrame last_;
  ros::WallTime last_sync_warning_;
  CauseThrottle skip_warnings_{kSkipWarning};  // why frames are skipped, one slot per cause
};

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

std::string OdometryNodelet::baseFrame() const {
  return settings_.base_frame_id.empty() ? camera_frame_ : settings_.base_frame_id;
}

bool OdometryNodelet::baseIsCamera() const {
  return settings_.base_is_optical_frame || baseFrame() == camera_frame_;
}

std::optional<Eigen::Isometry3d> OdometryNodelet::lookup(const std::string& target,
                                                         const std::string& source,
                                                         const ros::Time& stamp, double wait,
                                                         std::string* error) {
  // Poll on wall time: under use_sim_time a paused clock must not stall the callback.
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wait);
  while (true) {
    error->clear();  // canTransform appends
    if (tf_buffer_->canTransform(target, source, stamp, error)) {
      return tf2::transformToEigen(tf_buffer_->lookupTransform(target, source, stamp));
    }
    if (ros::WallTime::now() >= deadline) return std::nullopt;
    ros::WallDuration(0.005).sleep();
  }
}

std::optional<Eigen::Isometry3d> OdometryNodelet::baseFromCamera() {
  if (baseIsCamera()) return Eigen::Isometry3d::Identity();
  if (base_from_camera_) return base_from_camera_;
  const std::string base = baseFrame();
  std::string error;
  // Wait for it once (the static transform may come a moment after the first image), then only
  // look: waiting frame after frame would stall the callback queue.
  const double wait = base_waited_ ? 0.0 : settings_.wait_for_transform_duration;
  base_waited_ = true;
  base_from_camera_ = lookup(base, camera_frame_, ros::Time(0), wait, &error);
  if (base_from_camera_) {
    NODELET_INFO("camera '%s' in base '%s': looked up once", camera_frame_.c_str(), base.c_str());
  } else {
    NODELET_ERROR_THROTTLE(5.0,
                           "no transform from base frame '%s' to camera frame '%s' (%s): "
                           "odometry runs but is not published until it is available",
                           base.c_str(), camera_frame_.c_str(), error.c_str());
  }
  return base_from_camera_;
}

OdometryNodelet::FrameTf OdometryNodelet::frameTf(const ros::Time& stamp) {
  FrameTf tf;
  tf.base_from_camera = baseFromCamera();
  if (settings_.guess_frame_id.empty() || !tf.base_from_camera) return tf;
  const std::string& guess = settings_.guess_frame_id;
  const std::string base = baseFrame();
  std::string error;
  // Wait for the guess frame's transform at this stamp (wheel odometry may come a little after
  // the image), but not frame after frame while it is missing: that would stall every frame.
  const double wait = guess_found_ ? settings_.wait_for_transform_duration : 0.0;
  tf.guess_from_base = lookup(guess, base, stamp, wait, &error);
  guess_found_ = tf.guess_from_base.has_value();
  const std::optional<double> last = odometry_->lastTrackedStamp();
  if (tf.guess_from_base && last) {
    ros::Time then;
    then.fromSec(*last);
    const std::optional<Eigen::Isometry3d> before = lookup(guess, base, then, 0.0, &error);
    if (before) {
      // The base's motion from the last tracked frame to this one, seen from the camera.
      tf.motion_guess =
          conjugate(tf.base_from_camera->inverse(), before->inverse() * *tf.guess_from_base);
    }
  }
  if (!tf.guess_from_base || (last && !tf.motion_guess)) {
    NODELET_WARN_THROTTLE(kGuessWarning,
                          "no motion guess from '%s' to '%s' at %.6f (%s): the constant-velocity "
                          "prior is used%s",
                          guess.c_str(), base.c_str(), stamp.toSec(), error.c_str(),
                          tf.guess_from_base ? "" : ", and the correction is not published");
  }
  return tf;
}

void OdometryNodelet::publish(const acvo::OdometryResult& r, const ContinuousOdom::Pose& pose,
                              const std_msgs::Header& header, const FrameTf& tf) {
  if (!tf.base_from_camera) return;
  const Eigen::Isometry3d& base_from_camera = *tf.base_from_camera;
  const std::string base = baseFrame();
  std_msgs::Header odom_header;
  odom_header.stamp = header.stamp;
  odom_header.frame_id = settings_.odom_frame_id;
  // The published pose is continuous through losses (odom_continuity.hpp).
  acvo::OdometryResult published = r;
  published.pose = pose.pose;
  published.pose_covariance = pose.covariance;
  const bool lost = r.tracking == acvo::Tracking::kLost;
  if (lost && settings_.lost_odom == LostOdom::kNull) {
    odom_pub_.publish(nullOdometryMsg(odom_header, base));
  } else if (!(lost && settings_.lost_odom == LostOdom::kNone)) {
    odom_pub_.publish(toOdometryMsg(published, base_from_camera, odom_header, base));
  }
  // TF goes on whatever lost_odom says: a frame tree that stops would make every consumer's
  // lookups fail (extrapolation errors) for as long as tracking is lost.
  const Eigen::Isometry3d base_pose = conjugate(base_from_camera, pose.pose);
  if (settings_.publish_tf && settings_.guess_frame_id.empty()) {
    tf_broadcaster_->sendTransform(
        toTransformMsg(base_pose, settings_.odom_frame_id, base, header.stamp));
  } else if (settings_.publish_tf && tf.guess_from_base) {
    // odom -> guess -> base: the correction of the guess frame, so that the chain gives the
    // estimate and the base keeps its one parent (the wheel odometry's frame). While lost the
    // estimate follows the guess, so the correction stays as it was and the base goes on
    // with the wheels.
    tf_broadcaster_->sendTransform(toTransformMsg(base_pose * tf.guess_from_base->inverse(),
                                                  settings_.odom_frame_id,
                                                  settings_.guess_frame_id, header.stamp));
  }
  std_msgs::Header cloud_header = header;
  if (settings_.base_is_optical_frame) cloud_header.frame_id = base;  // the estimated camera
  if (r.cloud && cloud_pub_.getNumSubscribers() > 0) {
    cloud_pub_.publish(toPointCloud2(*r.cloud, cloud_header));
  }
  // The keyframe's cloud, in its own camera frame at its own stamp, once per keyframe.
  const std::uint64_t keyframe = r.new_keyframe ? r.frame_index : r.keyframe_index;
  const acvo::LabelledCloud* keyframe_cloud = odometry_->keyframeCloud();
  if (keyframe_cloud && published_keyframe_ != keyframe &&
      keyframe_cloud_pub_.getNumSubscribers() > 0) {
    cloud_header.stamp.fromSec(keyframe_cloud->stamp);
    keyframe_cloud_pub_.publish(toPointCloud2(*keyframe_cloud, cloud_header));
    published_keyframe_ = keyframe;
  }
}

void OdometryNodelet::publishInfo(const acvo::OdometryResult& r, const std_msgs::Header& header,
                                  const InfoExtras& extras) {
  last_.ms_total = extras.ms_total;
  last_.ms_latency = extras.ms_latency;
  info_pub_.publish(toInfoMsg(r, header, extras));
}

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

PLUGINLIB_EXPORT_CLASS(acvo_ros::OdometryNodelet, nodelet::Nodelet)
