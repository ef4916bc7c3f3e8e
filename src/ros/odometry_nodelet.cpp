// The ROS face of acvo: synchronised colour + depth + camera info in, odometry, TF, the
// labelled cloud, a per-frame report and diagnostics out. The nodelet converts messages, calls
// acvo::Odometry and publishes; the method lives in the core library.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

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
#include "acvo/odometry.hpp"
#include "cause_throttle.hpp"
#include "conversions.hpp"
#include "covariance.hpp"
#include "messages.hpp"
#include "ros_params.hpp"
#include "stamp_check.hpp"

namespace acvo_ros {

using sensor_msgs::CameraInfoConstPtr;
using sensor_msgs::ImageConstPtr;

namespace {
// A stamp earlier than the last one by more than this (s) is a restarted bag, not a reordering.
constexpr double kTimeJumpBack = 1.0;
// Warn when the synchroniser has produced nothing for this long (wall seconds).
constexpr double kNoSyncWarning = 5.0;
// Period of the warning about each cause of a skipped frame (s).
constexpr double kSkipWarning = 5.0;

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}
}  // namespace

class OdometryNodelet : public nodelet::Nodelet {
 private:
  using Image = sensor_msgs::Image;
  using Info = sensor_msgs::CameraInfo;
  using ExactPolicy = message_filters::sync_policies::ExactTime<Image, Image, Info>;
  using ApproxPolicy = message_filters::sync_policies::ApproximateTime<Image, Image, Info>;

  void onInit() override;
  void loadParameters();
  void subscribe();

  void onFrame(const ImageConstPtr& rgb, const ImageConstPtr& depth,
               const CameraInfoConstPtr& info);
  void processFrame(const Image& rgb, const Image& depth, const Info& info);
  bool acceptStamp(const ros::Time& stamp);
  std::optional<acvo::Frame> toFrame(const Image& rgb, const Image& depth, const Info& info);
  std::string baseFrame() const;
  std::optional<Eigen::Isometry3d> baseFromCamera();
  void publish(const acvo::OdometryResult& r, const std_msgs::Header& header);
  void publishInfo(const acvo::OdometryResult& r, const std_msgs::Header& header, double ms_total);
  void rejectFrame(const std_msgs::Header& header, const std::string& why, double ms_total);
  void restart(const Eigen::Isometry3d& camera_pose);

  bool onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool onResetToPose(acvo::ResetToPose::Request& req, acvo::ResetToPose::Response& res);
  void onReconfigure(acvo::AcvoConfig& config, uint32_t level);
  void onWatchdog(const ros::WallTimerEvent&);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  // Settings (set in onInit, publish_null_when_lost also by dynamic_reconfigure).
  std::string odom_frame_, base_frame_param_;
  bool base_is_optical_ = false;  // base_frame_param_ renames the optical frame: no lookup
  bool publish_tf_ = true;
  double wait_for_transform_ = 0.2;
  double max_time_gap_ = 1.0;
  double no_data_timeout_ = 3.0;
  bool publish_null_when_lost_ = false;
  IntrinsicsOverride intrinsics_;

  ros::NodeHandle nh_, pnh_;
  std::unique_ptr<image_transport::ImageTransport> it_;
  image_transport::SubscriberFilter rgb_sub_, depth_sub_;
  message_filters::Subscriber<Info> info_sub_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproxPolicy>> approx_sync_;
  ros::Publisher odom_pub_, cloud_pub_, keyframe_cloud_pub_, info_pub_;
  ros::ServiceServer reset_srv_, reset_to_pose_srv_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<acvo::AcvoConfig>> reconfigure_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer watchdog_;

  // State, guarded by mutex_ (frames, services, reconfigure and timers may run concurrently
  // when the manager has several worker threads).
  std::mutex mutex_;
  acvo::Params params_;
  std::unique_ptr<acvo::Odometry> odometry_;
  std::string camera_frame_;                           // optical frame of the last image
  std::optional<Eigen::Isometry3d> base_from_camera_;  // looked up once per camera frame
  ros::Time last_stamp_;                               // stamp of the last frame processed
  std::uint32_t lost_count_ = 0;
  std::uint64_t frames_ = 0;                         // frames given to the odometry
  std::optional<std::uint64_t> published_keyframe_;  // last keyframe sent on keyframe_cloud
  bool synchronised_ = false;                        // a frame came out of the synchroniser
  acvo::Tracking last_tracking_ = acvo::Tracking::kFirstFrame;
  std::string last_message_;
  double last_ms_total_ = 0.0;
  ros::WallTime last_frame_wall_;  // last synchronised frame, good or bad
  std::atomic<std::uint64_t> rgb_count_{0}, depth_count_{0}, info_count_{0};
  ros::WallTime last_sync_warning_;
  CauseThrottle skip_warnings_{kSkipWarning};  // why frames are skipped, one slot per cause
};

void OdometryNodelet::onInit() {
  nh_ = getNodeHandle();
  pnh_ = getPrivateNodeHandle();
  loadParameters();

  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odom", 10);
  cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("cloud", 2);
  // Latched: the keyframe changes seldom, a late subscriber still gets the current one.
  keyframe_cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("keyframe_cloud", 1, true);
  info_pub_ = nh_.advertise<acvo::OdometryInfo>("odom_info", 10);
  reset_srv_ = nh_.advertiseService("reset_odom", &OdometryNodelet::onReset, this);
  reset_to_pose_srv_ =
      nh_.advertiseService("reset_odom_to_pose", &OdometryNodelet::onResetToPose, this);
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh_);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();

  // Start the server from the loaded values rather than from the .cfg defaults.
  reconfigure_ =
      std::make_unique<dynamic_reconfigure::Server<acvo::AcvoConfig>>(reconfigure_mutex_, pnh_);
  reconfigure_->updateConfig(toConfig(params_, publish_null_when_lost_));
  reconfigure_->setCallback(
      [this](acvo::AcvoConfig& config, uint32_t level) { onReconfigure(config, level); });

  updater_ = std::make_unique<diagnostic_updater::Updater>(nh_, pnh_, getName());
  updater_->setHardwareID("acvo");
  updater_->add("odometry", this, &OdometryNodelet::diagnose);

  subscribe();
  last_sync_warning_ = last_frame_wall_ = ros::WallTime::now();
  watchdog_ = nh_.createWallTimer(ros::WallDuration(1.0), &OdometryNodelet::onWatchdog, this);
}

void OdometryNodelet::loadParameters() {
  pnh_.param<std::string>("odom_frame_id", odom_frame_, "odom");
  odom_frame_ = stripSlash(odom_frame_);
  pnh_.param<std::string>("base_frame_id", base_frame_param_, "");
  base_frame_param_ = stripSlash(base_frame_param_);
  pnh_.param("base_is_optical_frame", base_is_optical_, false);
  pnh_.param("publish_tf", publish_tf_, true);
  pnh_.param("wait_for_transform_duration", wait_for_transform_, 0.2);
  pnh_.param("max_time_gap", max_time_gap_, 1.0);
  pnh_.param("no_data_timeout", no_data_timeout_, 3.0);
  pnh_.param("publish_null_when_lost", publish_null_when_lost_, false);
  pnh_.param<std::string>("camera", intrinsics_.camera, "");
  pnh_.param("fx", intrinsics_.fx, 0.0);
  pnh_.param("fy", intrinsics_.fy, 0.0);
  pnh_.param("cx", intrinsics_.cx, 0.0);
  pnh_.param("cy", intrinsics_.cy, 0.0);
  const std::string intrinsics_problem = intrinsics_.problem();
  if (!intrinsics_problem.empty()) {
    NODELET_ERROR("%s: ignoring the override, intrinsics come from camera_info",
                  intrinsics_problem.c_str());
    intrinsics_ = IntrinsicsOverride();
  }

  XmlRpc::XmlRpcValue private_ns;
  ros::param::get(pnh_.getNamespace(), private_ns);
  acvo::Params params;
  for (const std::string& problem : applyRosParams(private_ns, params)) {
    NODELET_ERROR("parameter problem: %s", problem.c_str());
  }
  const std::string invalid = acvo::validate(params);
  if (!invalid.empty()) {
    NODELET_ERROR("invalid parameters (%s): using the defaults of acvo::Params instead",
                  invalid.c_str());
    params = acvo::Params();
  }
  params_ = params;
  odometry_ = std::make_unique<acvo::Odometry>(params_);
  NODELET_INFO("acvo parameters: %s", describeParams(params_).c_str());
}

void OdometryNodelet::subscribe() {
  bool approx = true;
  double max_interval = 0.0;
  int queue_size = 10;
  pnh_.param("approx_sync", approx, true);
  pnh_.param("approx_sync_max_interval", max_interval, 0.0);
  pnh_.param("queue_size", queue_size, 10);
  queue_size = std::max(queue_size, 1);

  it_ = std::make_unique<image_transport::ImageTransport>(nh_);
  const image_transport::TransportHints rgb_hints("raw", ros::TransportHints(), pnh_,
                                                  "image_transport");
  const image_transport::TransportHints depth_hints("raw", ros::TransportHints(), pnh_,
                                                    "depth_image_transport");
  rgb_sub_.subscribe(*it_, "rgb/image", queue_size, rgb_hints);
  depth_sub_.subscribe(*it_, "depth/image", queue_size, depth_hints);
  info_sub_.subscribe(nh_, "rgb/camera_info", queue_size);
  rgb_sub_.registerCallback(
      boost::function<void(const ImageConstPtr&)>([this](const ImageConstPtr&) { ++rgb_count_; }));
  depth_sub_.registerCallback(boost::function<void(const ImageConstPtr&)>(
      [this](const ImageConstPtr&) { ++depth_count_; }));
  info_sub_.registerCallback(boost::function<void(const CameraInfoConstPtr&)>(
      [this](const CameraInfoConstPtr&) { ++info_count_; }));

  using namespace boost::placeholders;
  const auto callback = boost::bind(&OdometryNodelet::onFrame, this, _1, _2, _3);
  if (approx) {
    approx_sync_ = std::make_unique<message_filters::Synchronizer<ApproxPolicy>>(
        ApproxPolicy(queue_size), rgb_sub_, depth_sub_, info_sub_);
    if (max_interval > 0.0) approx_sync_->setMaxIntervalDuration(ros::Duration(max_interval));
    approx_sync_->setReset(true);  // clear the queues when a replayed clock jumps back
    approx_sync_->registerCallback(callback);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(queue_size), rgb_sub_, depth_sub_, info_sub_);
    exact_sync_->setReset(true);
    exact_sync_->registerCallback(callback);
  }
  NODELET_INFO("subscribed to %s, %s, %s (%s sync, queue %d)", rgb_sub_.getTopic().c_str(),
               depth_sub_.getTopic().c_str(), info_sub_.getTopic().c_str(),
               approx ? "approximate" : "exact", queue_size);
}

void OdometryNodelet::onFrame(const ImageConstPtr& rgb, const ImageConstPtr& depth,
                              const CameraInfoConstPtr& info) {
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    processFrame(*rgb, *depth, *info);
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(5.0, "frame at %.6f skipped: %s", rgb->header.stamp.toSec(), e.what());
  }
}

void OdometryNodelet::processFrame(const Image& rgb, const Image& depth, const Info& info) {
  const auto start = std::chrono::steady_clock::now();
  last_frame_wall_ = ros::WallTime::now();
  synchronised_ = true;
  std_msgs::Header header = rgb.header;
  header.frame_id = stripSlash(rgb.header.frame_id);
  if (!acceptStamp(header.stamp)) return;

  std::optional<acvo::Frame> frame = toFrame(rgb, depth, info);
  if (!frame) return;
  if (header.frame_id != camera_frame_) {
    camera_frame_ = header.frame_id;
    base_from_camera_.reset();
  }

  const acvo::OdometryResult r = odometry_->process(*frame);
  ++frames_;
  last_tracking_ = r.tracking;
  last_message_ = r.message;
  if (r.tracking == acvo::Tracking::kBadFrame) {
    if (skip_warnings_.allow(r.message, ros::WallTime::now().toSec())) {
      NODELET_WARN("frame rejected by the odometry: %s", r.message.c_str());
    }
    publishInfo(r, header, msSince(start));
    return;
  }
  last_stamp_ = header.stamp;

  if (r.tracking == acvo::Tracking::kLost) {
    ++lost_count_;
    NODELET_WARN_THROTTLE(2.0, "tracking lost (%s): holding the last pose, %s (%u lost so far)",
                          r.message.c_str(),
                          r.new_keyframe ? "the reference restarts from this frame"
                                         : "the next frame is registered to the last good one",
                          lost_count_);
  }
  publish(r, header);
  publishInfo(r, header, msSince(start));
}

bool OdometryNodelet::acceptStamp(const ros::Time& stamp) {
  const double last = last_stamp_.toSec();
  switch (checkStamp(last, stamp.toSec(), max_time_gap_, kTimeJumpBack)) {
    case StampVerdict::kAccept:
      return true;
    case StampVerdict::kGap:
      NODELET_WARN_THROTTLE(5.0,
                            "%.3f s between frames (max_time_gap %.3f): continuing, the motion "
                            "guess may be poor",
                            stamp.toSec() - last, max_time_gap_);
      return true;
    case StampVerdict::kDrop:
      NODELET_WARN_THROTTLE(5.0, "dropping a frame whose stamp %.6f is not after the last one %.6f",
                            stamp.toSec(), last);
      return false;
    case StampVerdict::kRestart:
      NODELET_WARN("time jumped back by %.3f s (bag restarted?): odometry restarts at identity",
                   last - stamp.toSec());
      restart(Eigen::Isometry3d::Identity());
      last_stamp_ = ros::Time();
      return true;
  }
  return false;
}

void OdometryNodelet::rejectFrame(const std_msgs::Header& header, const std::string& why,
                                  double ms_total) {
  last_tracking_ = acvo::Tracking::kBadFrame;
  last_message_ = why;
  if (skip_warnings_.allow(why, ros::WallTime::now().toSec())) {
    NODELET_WARN("frame skipped: %s", why.c_str());
  }
  acvo::OdometryResult r;
  r.tracking = acvo::Tracking::kBadFrame;
  r.message = why;
  publishInfo(r, header, ms_total);
}

std::optional<acvo::Frame> OdometryNodelet::toFrame(const Image& rgb, const Image& depth,
                                                    const Info& info) {
  const auto start = std::chrono::steady_clock::now();
  std_msgs::Header header = rgb.header;
  header.frame_id = stripSlash(rgb.header.frame_id);
  if (header.frame_id.empty()) {
    rejectFrame(header, "the colour image on " + rgb_sub_.getTopic() + " has no frame_id",
                msSince(start));
    return std::nullopt;
  }
  ColorImage color = decodeColor(rgb);
  if (!color.problem.empty()) {
    rejectFrame(header, color.problem + " on " + rgb_sub_.getTopic(), msSince(start));
    return std::nullopt;
  }
  if (color.order == acvo::ColorOrder::kGray) {
    NODELET_WARN_ONCE("%s is mono8: points get intensity and gradient labels but no colour",
                      rgb_sub_.getTopic().c_str());
  }
  DepthImage metres = decodeDepth(depth);
  if (!metres.problem.empty()) {
    rejectFrame(header, metres.problem + " on " + depth_sub_.getTopic(), msSince(start));
    return std::nullopt;
  }
  if (rgb.width != depth.width || rgb.height != depth.height) {
    rejectFrame(header,
                "colour (" + rgb_sub_.getTopic() + ", " + std::to_string(rgb.width) + "x" +
                    std::to_string(rgb.height) + ") and depth (" + depth_sub_.getTopic() + ", " +
                    std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                    ") differ in size: the depth must be registered to the colour image",
                msSince(start));
    return std::nullopt;
  }
  CameraResult camera = cameraFor(info, rgb.width, rgb.height, intrinsics_);
  if (!camera.problem.empty()) {
    rejectFrame(header, camera.problem + " (" + info_sub_.getTopic() + ")", msSince(start));
    return std::nullopt;
  }
  if (!intrinsics_.named() && !intrinsics_.explicitValues() &&
      std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0.0; })) {
    NODELET_WARN_ONCE("%s has non-zero distortion: the images are used as if rectified",
                      info_sub_.getTopic().c_str());
  }
  acvo::Frame frame;
  frame.color = color.image;
  frame.order = color.order;
  frame.depth = metres.metres;
  frame.camera = camera.camera;
  frame.stamp = rgb.header.stamp.toSec();
  const std::string problem = frame.problem();
  if (!problem.empty()) {
    rejectFrame(header, problem, msSince(start));
    return std::nullopt;
  }
  return frame;
}

std::string OdometryNodelet::baseFrame() const {
  return base_frame_param_.empty() ? camera_frame_ : base_frame_param_;
}

std::optional<Eigen::Isometry3d> OdometryNodelet::baseFromCamera() {
  const std::string base = baseFrame();
  if (base_is_optical_ || base == camera_frame_) return Eigen::Isometry3d::Identity();
  if (base_from_camera_) return base_from_camera_;
  // Poll on wall time: under use_sim_time a paused clock must not stall the callback.
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wait_for_transform_);
  std::string error;
  while (true) {
    error.clear();  // canTransform appends
    if (tf_buffer_->canTransform(base, camera_frame_, ros::Time(0), &error)) {
      base_from_camera_ =
          tf2::transformToEigen(tf_buffer_->lookupTransform(base, camera_frame_, ros::Time(0)));
      NODELET_INFO("camera '%s' in base '%s': looked up once", camera_frame_.c_str(), base.c_str());
      return base_from_camera_;
    }
    if (ros::WallTime::now() >= deadline) break;
    ros::WallDuration(0.005).sleep();
  }
  NODELET_ERROR_THROTTLE(5.0,
                         "no transform from base frame '%s' to camera frame '%s' (%s): odometry "
                         "is not published until it is available",
                         base.c_str(), camera_frame_.c_str(), error.c_str());
  return std::nullopt;
}

void OdometryNodelet::publish(const acvo::OdometryResult& r, const std_msgs::Header& header) {
  const std::optional<Eigen::Isometry3d> base_from_camera = baseFromCamera();
  if (!base_from_camera) return;
  const std::string base = baseFrame();
  if (!(r.tracking == acvo::Tracking::kLost && publish_null_when_lost_)) {
    std_msgs::Header odom_header;
    odom_header.stamp = header.stamp;
    odom_header.frame_id = odom_frame_;
    const nav_msgs::Odometry odom = toOdometryMsg(r, *base_from_camera, odom_header, base);
    odom_pub_.publish(odom);
    if (publish_tf_) {
      tf_broadcaster_->sendTransform(
          toTransformMsg(conjugate(*base_from_camera, r.pose), odom_frame_, base, header.stamp));
    }
  }
  std_msgs::Header cloud_header = header;
  if (base_is_optical_) cloud_header.frame_id = base;  // the estimated camera, not the sensor's
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
                                  double ms_total) {
  last_ms_total_ = ms_total;
  info_pub_.publish(toInfoMsg(r, header, ms_total, lost_count_));
}

void OdometryNodelet::restart(const Eigen::Isometry3d& camera_pose) {
  odometry_->reset(camera_pose);
  published_keyframe_.reset();
}

bool OdometryNodelet::onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    restart(Eigen::Isometry3d::Identity());
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
    std::optional<Eigen::Isometry3d> base_from_camera;
    if (base_is_optical_ || base_frame_param_.empty() || base_frame_param_ == camera_frame_) {
      base_from_camera = Eigen::Isometry3d::Identity();
    } else if (!camera_frame_.empty()) {
      base_from_camera = baseFromCamera();
    }
    if (!base_from_camera) {
      res.success = false;
      res.message = "the camera-to-base transform is not known yet (base frame '" +
                    base_frame_param_ + "', camera frame '" +
                    (camera_frame_.empty() ? std::string("none received yet") : camera_frame_) +
                    "')";
      return true;
    }
    // The engine holds the camera pose in the first camera's frame: undo the conjugation.
    restart(conjugate(base_from_camera->inverse(), base_pose));
    res.success = true;
    res.message = "odometry restarts from the given pose";
    NODELET_INFO("odometry reset to a given pose");
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
  }
  return true;
}

void OdometryNodelet::onReconfigure(acvo::AcvoConfig& config, uint32_t /*level*/) {
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    publish_null_when_lost_ = config.publish_null_when_lost;
    const acvo::Params next = fromConfig(config, params_);
    const std::string invalid = acvo::validate(next);
    if (!invalid.empty()) {
      NODELET_ERROR("dynamic_reconfigure: %s: keeping the previous parameters", invalid.c_str());
      // The server publishes what the callback leaves in `config`: show the values in use.
      config = toConfig(params_, publish_null_when_lost_);
      return;
    }
    if (describeParams(next) == describeParams(params_)) return;
    const Eigen::Isometry3d pose = odometry_->pose();
    const acvo::Matrix6d covariance = odometry_->poseCovariance();
    params_ = next;
    odometry_ = std::make_unique<acvo::Odometry>(params_);
    odometry_->reset(pose, covariance);
    published_keyframe_.reset();
    NODELET_INFO("parameters changed, tracking restarts from the current pose: %s",
                 describeParams(params_).c_str());
  } catch (const std::exception& e) {
    NODELET_ERROR("dynamic_reconfigure: %s: keeping the previous parameters", e.what());
    config = toConfig(params_, publish_null_when_lost_);
  }
}

void OdometryNodelet::onWatchdog(const ros::WallTimerEvent&) {
  try {
    updater_->force_update();
    const ros::WallTime now = ros::WallTime::now();
    std::lock_guard<std::mutex> lock(mutex_);
    const double silent = (now - last_frame_wall_).toSec();
    if (silent > kNoSyncWarning && (now - last_sync_warning_).toSec() > kNoSyncWarning) {
      last_sync_warning_ = now;
      NODELET_WARN(
          "no synchronised frame for %.0f s on %s, %s, %s (messages received so far: %lu, %lu, "
          "%lu)",
          silent, rgb_sub_.getTopic().c_str(), depth_sub_.getTopic().c_str(),
          info_sub_.getTopic().c_str(), static_cast<unsigned long>(rgb_count_.load()),
          static_cast<unsigned long>(depth_count_.load()),
          static_cast<unsigned long>(info_count_.load()));
    }
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(10.0, "watchdog: %s", e.what());
  }
}

void OdometryNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  const double silent = (ros::WallTime::now() - last_frame_wall_).toSec();
  const DiagnosticSummary summary =
      summarise(synchronised_, silent, no_data_timeout_, last_tracking_);
  stat.summary(summary.level, summary.message);
  stat.add("seconds since last frame", silent);
  stat.add("frames processed", frames_);
  stat.add("frames lost", lost_count_);
  stat.add("last tracking", acvo::toString(last_tracking_));
  stat.add("last message", last_message_);
  stat.add("last ms total", last_ms_total_);
  stat.add("messages received (rgb, depth, info)", std::to_string(rgb_count_.load()) + ", " +
                                                       std::to_string(depth_count_.load()) + ", " +
                                                       std::to_string(info_count_.load()));
}

}  // namespace acvo_ros

PLUGINLIB_EXPORT_CLASS(acvo_ros::OdometryNodelet, nodelet::Nodelet)
