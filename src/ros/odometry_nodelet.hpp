// The ROS face of acvo: synchronised colour + depth + camera info in, odometry, TF, the
// labelled cloud, a per-frame report and diagnostics out. The nodelet converts messages, calls
// acvo::Odometry and publishes; the method lives in the core library.
//
// One frame's path: onFrame (lock) -> processFrame: stamp rules, conversion, the camera-to-base
// transform, the motion guess from TF, the odometry, then publish() and publishInfo(). A frame
// that is not processed (its stamp, its messages, the odometry's own checks, an exception) goes
// through reject(), the one place: a named cause in odom_info, the log and diagnostics. Only
// frames dropped on request (pause_odom) are not reported one by one.
#pragma once

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

// A stamp earlier than the last one by more than this (s) is a restarted stream, not a
// reordering (StampGuard also tells a shorter jump back from a reordering).
inline constexpr double kTimeJumpBack = 1.0;
// Warn when the synchroniser has produced nothing for this long (wall seconds).
inline constexpr double kNoSyncWarning = 5.0;
// Period of the warning about each cause of a skipped frame (s).
inline constexpr double kSkipWarning = 5.0;
// Period of the warning about a motion guess that could not be looked up (s).
inline constexpr double kGuessWarning = 10.0;
// Period of the note on the camera intrinsics in use, when they change (s).
inline constexpr double kCameraNote = 5.0;

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

}  // namespace acvo_ros
