// Synthetic RGB-D frames with known motion through the odometry nodelet (rostest + gtest).
//
// The .test file starts the nodelet with the camera topics remapped to cam/*, and sets the
// private parameters of this test: depth_encoding, color_encoding, approx (depth stamps offset
// from colour stamps), camera_frame (as sent, may carry a leading '/'), odom_frame and
// base_frame (expected ids), base_from_camera ("x y z qx qy qz qw" of the static transform the
// .test publishes; empty = base is the optical frame), exact_stamps (run the stamp tests, which
// need exact synchronisation: the approximate policy itself swallows reordered stamps),
// late_base_tf (the .test publishes no base transform; the test sends it itself, after checking
// that nothing is published without it), burst (run the burst test, whose stamps are the wall
// clock's, on a fresh nodelet), initial_pose (the nodelet's, when the .test sets one),
// guess_frame (the .test sets the nodelet's guess_frame_id to it: the test publishes the true
// base motion as that frame's wheel odometry), binned (camera_info of a 640x480 camera with
// 2x2 binning for the 320x240 images, and a raw-image K that differs from P), depth_frame (the
// depth images' frame_id, when it differs from the colour's), bad_params (the .test gives the
// nodelet a bad and an unknown parameter).
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <pcl_conversions/pcl_conversions.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "acvo/OdometryInfo.h"
#include "acvo/ResetToPose.h"
#include "acvo/params.hpp"
#include "conversions.hpp"
#include "covariance.hpp"
#include "nodelet_settings.hpp"
#include "point_types.hpp"
#include "synthetic_room.hpp"
#include "test_messages.hpp"

namespace {

using acvo_test::cameraPose;
using acvo_test::RgbdImage;

// What each check of a measured figure allows: kMargin times the figure measured at that check,
// the largest over the .test configurations that run it (acvo_synthetic room at 320x240, 1500
// points, 1.5 cm and 0.6 deg of motion per frame, exact depth), so that a regression of the
// engine or of the nodelet fails it. The figures (the `Measured{}` and `k...Measured` values
// below) are what scripts/measure_ros_bounds printed: it runs the .test files and sets each
// `[ BOUND ]` line's figure, the largest over the configurations, beside its bound. The 16-bit
// configuration's millimetre depth steps set most of them; the float one's errors are smaller.
// Poses that must be exact (the origin, a held pose) use kExactPose. Timing checks (`[ TIMING ]`)
// are no multiple of a measurement: each says what it catches.
struct Measured {
  double t = 0.0;  // m
  double r = 0.0;  // rad
};
constexpr double kMargin = 2.5;
constexpr Measured kExactPose{};
// Figures of checks that are not a pose's (scripts/measure_ros_bounds).
constexpr double kTwistMeasured = 0.000396;            // m/s
constexpr double kAfterInvalidMeasured = 0.0000174;     // m
constexpr Measured kAfterBlackoutMeasured{0.0000248, 0.00000884};
constexpr double kTwistAfterNoiseMeasured = 0.00107;    // m/s
constexpr int kTrackFrames = 12;
constexpr double kExact = 1e-9;
constexpr double kOutcomeTimeout = 20.0;  // s, one frame through a loaded machine
// Latency beyond the frames' processing: transport and scheduling on a loaded machine (ms).
constexpr double kLatencySlack = 100.0;
// Frames a new one may wait for with topic_queue_size 2: the one in progress, two queued and
// one in the synchroniser, plus its own processing.
constexpr double kQueuedFrames = 5.0;

double angleOf(const Eigen::Matrix3d& r) {
  return Eigen::AngleAxisd(r).angle();
}

// A registered frame: "hard" is still tracking (the engine says so when, e.g., the length-scale
// ends at its lower bound, which it does on noise-free frames).
bool isTracking(const std::string& tracking) {
  return tracking == "ok" || tracking == "hard";
}

// The diagnostic the nodelet should show after a frame judged `tracking`.
std::pair<std::uint8_t, std::string> diagnosticFor(const std::string& tracking) {
  using diagnostic_msgs::DiagnosticStatus;
  if (tracking == "hard") return {DiagnosticStatus::WARN, "hard to track"};
  if (tracking == "lost") return {DiagnosticStatus::ERROR, "lost"};
  return {DiagnosticStatus::OK, "tracking"};
}

Eigen::Isometry3d toEigen(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d t;
  tf2::fromMsg(p, t);
  return t;
}

struct Outcome {
  std::optional<acvo::OdometryInfo> info;
  std::optional<nav_msgs::Odometry> odom;
};

// Everything the test sends and receives, shared by the test cases (one nodelet per .test).
class Client {
 public:
  Client() : pnh_("~"), tf_listener_(tf_buffer_) {
    depth_encoding_ = pnh_.param<std::string>("depth_encoding", "32FC1");
    color_encoding_ = pnh_.param<std::string>("color_encoding", "rgb8");
    approx_ = pnh_.param("approx", true);
    camera_frame_ = pnh_.param<std::string>("camera_frame", "cam_rgb_optical_frame");
    odom_frame_ = pnh_.param<std::string>("odom_frame", "odom");
    base_frame_ = pnh_.param<std::string>("base_frame", acvo_ros::stripSlash(camera_frame_));
    exact_stamps_ = pnh_.param("exact_stamps", false);
    late_base_tf_ = pnh_.param("late_base_tf", false);
    burst_ = pnh_.param("burst", false);
    initial_pose_ = acvo_ros::parsePose6(pnh_.param<std::string>("initial_pose", ""), nullptr);
    guess_frame_ = pnh_.param<std::string>("guess_frame", "");
    binned_ = pnh_.param("binned", false);
    depth_frame_ = pnh_.param<std::string>("depth_frame", camera_frame_);
    bad_params_ = pnh_.param("bad_params", false);
    base_from_camera_ = Eigen::Isometry3d::Identity();
    std::istringstream tf(pnh_.param<std::string>("base_from_camera", ""));
    double x, y, z, qx, qy, qz, qw;
    if (tf >> x >> y >> z >> qx >> qy >> qz >> qw) {
      base_from_camera_.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().matrix();
      base_from_camera_.translation() << x, y, z;
    }
    rgb_pub_ = nh_.advertise<sensor_msgs::Image>("cam/rgb", 20);
    depth_pub_ = nh_.advertise<sensor_msgs::Image>("cam/depth", 20);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("cam/info", 20);
    odom_sub_ = nh_.subscribe("odom", 100, &Client::onOdom, this);
    info_sub_ = nh_.subscribe("odom_info", 100, &Client::onInfo, this);
    diag_sub_ = nh_.subscribe("/diagnostics", 100, &Client::onDiagnostics, this);
    rosout_sub_ = nh_.subscribe("/rosout", 1000, &Client::onLog, this);
    reset_ = nh_.serviceClient<std_srvs::Empty>("reset_odom");
    reset_to_pose_ = nh_.serviceClient<acvo::ResetToPose>("reset_odom_to_pose");
    next_stamp_ = ros::Time::now();
  }

  // Waits until the nodelet is connected both ways.
  bool connect() {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
    while (ros::WallTime::now() < deadline) {
      if (rgb_pub_.getNumSubscribers() > 0 && depth_pub_.getNumSubscribers() > 0 &&
          info_pub_.getNumSubscribers() > 0 && odom_sub_.getNumPublishers() > 0 &&
          info_sub_.getNumPublishers() > 0 && reset_.exists()) {
        return true;
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }

  // Waits until this client's TF listener can hear another node on /tf (its own broadcaster is
  // one publisher there): a listener connected after the first frames were sent misses their
  // transforms, and on a loaded machine that took longer than four frames.
  bool tfFromAnotherNode() {
    ros::Subscriber probe = nh_.subscribe("/tf", 1, &Client::ignoreTf, this);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
    while (ros::WallTime::now() < deadline) {
      if (probe.getNumPublishers() >= 2) {
        ros::WallDuration(0.2).sleep();  // the listener's own link, made at the same notice
        return true;
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }
  void ignoreTf(const tf2_msgs::TFMessage::ConstPtr&) {}

  ros::Time nextStamp() {
    next_stamp_ += ros::Duration(0.1);
    return next_stamp_;
  }
  // A pause in the stream: the next stamp comes `seconds` later than it would have.
  void skipTime(double seconds) { next_stamp_ += ros::Duration(seconds); }

  // The three messages of a frame, built ahead of publishing (a burst is then quick).
  struct Messages {
    sensor_msgs::ImagePtr rgb, depth;
    sensor_msgs::CameraInfoPtr info;
  };
  Messages messages(const RgbdImage& img, const ros::Time& stamp) {
    std_msgs::Header h;
    h.stamp = stamp;
    h.frame_id = camera_frame_;
    std_msgs::Header dh = h;
    dh.frame_id = depth_frame_;
    if (approx_) dh.stamp += ros::Duration(0.007);
    return {acvo_test::colorMsg(img.rgb, color_encoding_, h),
            acvo_test::depthMsg(img.depth, depth_encoding_, dh), cameraInfo(h)};
  }
  // The camera_info sent with each frame: the test camera's, or (binned) a 640x480 camera with
  // 2x2 binning whose P gives the test camera and whose K (the raw image's) does not.
  sensor_msgs::CameraInfoPtr cameraInfo(const std_msgs::Header& h) const {
    sensor_msgs::CameraInfoPtr info = acvo_test::infoMsg(acvo_test::testCamera(), h);
    if (!binned_) return info;
    const acvo::Camera c = acvo_test::testCamera();
    info->width = 2 * c.width;
    info->height = 2 * c.height;
    info->binning_x = info->binning_y = 2;
    info->K = {2 * c.fx + 40, 0, 2 * c.cx + 12, 0, 2 * c.fy + 40, 2 * c.cy - 9, 0, 0, 1};
    info->P = {2 * c.fx, 0, 2 * c.cx, 0, 0, 2 * c.fy, 2 * c.cy, 0, 0, 0, 1, 0};
    return info;
  }
  // Publishes the wheel odometry of a frame: guess_frame -> base at `stamp`.
  void sendGuess(const Eigen::Isometry3d& base_pose, const ros::Time& stamp) {
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(base_pose);
    t.header.stamp = stamp;
    t.header.frame_id = guess_frame_;
    t.child_frame_id = base_frame_;
    tf_broadcaster_.sendTransform(t);
  }
  void publish(const Messages& m) {
    info_pub_.publish(m.info);
    depth_pub_.publish(m.depth);
    rgb_pub_.publish(m.rgb);
  }

  // Publishes one frame; `mutate` may spoil any of the three messages.
  template <typename Mutate>
  void send(const RgbdImage& img, const ros::Time& stamp, Mutate&& mutate) {
    std_msgs::Header h;
    h.stamp = stamp;
    h.frame_id = camera_frame_;
    std_msgs::Header dh = h;
    dh.frame_id = depth_frame_;
    if (approx_) dh.stamp += ros::Duration(0.007);  // like TUM: depth a few ms after colour
    sensor_msgs::ImagePtr rgb = acvo_test::colorMsg(img.rgb, color_encoding_, h);
    sensor_msgs::ImagePtr depth = acvo_test::depthMsg(img.depth, depth_encoding_, dh);
    sensor_msgs::CameraInfoPtr info = cameraInfo(h);
    mutate(*rgb, *depth, *info);
    info_pub_.publish(info);
    depth_pub_.publish(depth);
    rgb_pub_.publish(rgb);
  }
  void send(const RgbdImage& img, const ros::Time& stamp) {
    send(img, stamp, [](auto&, auto&, auto&) {});
  }

  // The approximate policy holds a set back until a later message proves it the best match:
  // a later colour image and camera info (no depth, so no frame) release it.
  void flush() {
    if (!approx_) return;
    std_msgs::Header h;
    h.stamp = nextStamp();
    h.frame_id = camera_frame_;
    info_pub_.publish(cameraInfo(h));
    rgb_pub_.publish(acvo_test::colorMsg(frame(0).rgb, color_encoding_, h));
  }

  // Waits for what the nodelet said about the frame stamped `stamp`. `expect_odom`: also wait
  // for the odometry message (otherwise give it a moment to show that none comes).
  Outcome outcome(const ros::Time& stamp, bool expect_odom, double timeout = kOutcomeTimeout) {
    Outcome out;
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::WallTime::now() < deadline && !(out.info = infoAt(stamp))) {
      ros::WallDuration(0.002).sleep();
    }
    if (!out.info) return out;
    const ros::WallTime odom_deadline =
        ros::WallTime::now() + ros::WallDuration(expect_odom ? 2.0 : 0.3);
    while (ros::WallTime::now() < odom_deadline && !(out.odom = odomAt(stamp))) {
      ros::WallDuration(0.002).sleep();
    }
    return out;
  }

  // Sends frames k in `indices` (rendered once and cached) and returns their outcomes, keeping
  // one frame in flight so the approximate policy can release each set.
  std::vector<Outcome> run(const std::vector<int>& indices,
                           std::vector<ros::Time>* stamps = nullptr) {
    std::vector<RgbdImage> images;
    std::vector<ros::Time> sent;
    for (int k : indices) {
      images.push_back(frame(k));
      sent.push_back(nextStamp());
    }
    if (stamps) *stamps = sent;
    return run(images, sent);
  }
  // The same with the images and stamps given.
  // `guesses`: the base pose of each frame, published as the guess frame's wheel odometry.
  std::vector<Outcome> run(const std::vector<RgbdImage>& images,
                           const std::vector<ros::Time>& stamps,
                           const std::vector<Eigen::Isometry3d>& guesses = {}) {
    std::vector<Outcome> out;
    for (std::size_t i = 0; i < images.size(); ++i) {
      if (!guesses.empty()) {
        sendGuess(guesses[i], stamps[i]);
        ros::WallDuration(0.02).sleep();  // on TF before the frame, as wheel odometry would be
      }
      send(images[i], stamps[i]);
      if (i > 0) out.push_back(outcome(stamps[i - 1], true));
    }
    flush();
    out.push_back(outcome(stamps.back(), true));
    return out;
  }

  const RgbdImage& frame(int k) {
    auto it = frames_.find(k);
    if (it == frames_.end()) {
      it = frames_
               .emplace(k, acvo_test::renderRoom(acvo_test::worldFromFirstCamera() * cameraPose(k),
                                                 acvo_test::testCamera()))
               .first;
    }
    return it->second;
  }
  // All depth invalid.
  RgbdImage blank() {
    RgbdImage img = frame(0);
    RgbdImage out{img.rgb.clone(), cv::Mat::zeros(img.depth.size(), CV_32FC1)};
    return out;
  }

  // Frame k's depth with one colour everywhere: no intensity gradient to select points from.
  RgbdImage flatColour(int k) {
    return {cv::Mat(frame(k).rgb.size(), CV_8UC3, cv::Scalar(128, 128, 128)), frame(k).depth};
  }
  // Frame k's colour with depth beyond the range everywhere (60 m: under 16UC1's 65535, which is
  // no reading).
  RgbdImage farDepth(int k) {
    return {frame(k).rgb, cv::Mat(frame(k).depth.size(), CV_32FC1, cv::Scalar(60.0f))};
  }
  // Uniform random colour and depth (0.5-4 m): a frame of noise.
  RgbdImage noise(unsigned seed) {
    cv::RNG rng(seed);
    RgbdImage img{cv::Mat(frame(0).rgb.size(), CV_8UC3), cv::Mat(frame(0).depth.size(), CV_32FC1)};
    rng.fill(img.rgb, cv::RNG::UNIFORM, 0, 256);
    rng.fill(img.depth, cv::RNG::UNIFORM, 0.5, 4.0);
    return img;
  }

  // Waits for a warning or error on /rosout, logged after `since`, that contains `text`.
  std::optional<std::string> waitLog(const std::string& text, const ros::WallTime& since,
                                     double timeout = 5.0) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (true) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& [wall, msg] : logs_) {
          if (wall >= since && msg.find(text) != std::string::npos) return msg;
        }
      }
      if (ros::WallTime::now() >= deadline) return std::nullopt;
      ros::WallDuration(0.02).sleep();
    }
  }

  // How many warnings and errors on /rosout so far contain `text`.
  std::size_t countLogs(const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::count_if(logs_.begin(), logs_.end(), [&](const auto& log) {
      return log.second.find(text) != std::string::npos;
    });
  }

  bool reset() {
    std_srvs::Empty srv;
    return reset_.call(srv);
  }
  std::optional<acvo::ResetToPose::Response> resetTo(const Eigen::Isometry3d& pose) {
    acvo::ResetToPose srv;
    srv.request.pose = tf2::toMsg(pose);
    if (!reset_to_pose_.call(srv)) return std::nullopt;
    return srv.response;
  }

  // Expected published pose of camera pose `cam` (base frame conjugation).
  Eigen::Isometry3d expectedBase(const Eigen::Isometry3d& cam) const {
    return acvo_ros::conjugate(base_from_camera_, cam);
  }

  // The newest odometry diagnostic received after `after` (wall), if any.
  std::optional<diagnostic_msgs::DiagnosticStatus> diagnosticAfter(const ros::WallTime& after) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!last_diag_ || last_diag_wall_ < after) return std::nullopt;
    return last_diag_;
  }
  // Waits for an odometry diagnostic with this level and message; returns the last one seen.
  std::optional<diagnostic_msgs::DiagnosticStatus> waitDiagnostic(std::uint8_t level,
                                                                  const std::string& message,
                                                                  double timeout = 5.0) {
    const ros::WallTime start = ros::WallTime::now();
    std::optional<diagnostic_msgs::DiagnosticStatus> d;
    while ((ros::WallTime::now() - start).toSec() < timeout) {
      d = diagnosticAfter(start);
      if (d && d->level == level && d->message == message) return d;
      ros::WallDuration(0.05).sleep();
    }
    return d;
  }

  // The value of one entry of the newest odometry diagnostic, waiting for one to come.
  std::optional<std::string> diagnosticValue(const std::string& key, double timeout = 5.0) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::WallTime::now() < deadline) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (last_diag_) {
          for (const auto& kv : last_diag_->values) {
            if (kv.key == key) return kv.value;
          }
        }
      }
      ros::WallDuration(0.05).sleep();
    }
    return std::nullopt;
  }
  // The value of `key` in the first odometry diagnostic received after `since` (wall).
  std::optional<std::string> diagnosticValueAfter(const std::string& key,
                                                  const ros::WallTime& since,
                                                  double timeout = 5.0) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::WallTime::now() < deadline) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (last_diag_ && last_diag_wall_ > since) {
          for (const auto& kv : last_diag_->values) {
            if (kv.key == key) return kv.value;
          }
          return std::nullopt;
        }
      }
      ros::WallDuration(0.05).sleep();
    }
    return std::nullopt;
  }
  // The value of `key` once `done` holds for it, or the last one seen after `timeout` s
  // (diagnostics come once a second).
  template <typename Done>
  std::optional<std::string> diagnosticValueOnce(const std::string& key, Done&& done,
                                                 double timeout = 5.0) {
    std::optional<std::string> v;
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    do {
      v = diagnosticValue(key);
      if (v && done(*v)) break;
      ros::WallDuration(0.1).sleep();
    } while (ros::WallTime::now() < deadline);
    return v;
  }

  std::optional<geometry_msgs::TransformStamped> lookup(const ros::Time& stamp) {
    try {
      return tf_buffer_.lookupTransform(odom_frame_, base_frame_, stamp, ros::Duration(2.0));
    } catch (const tf2::TransformException&) {
      return std::nullopt;
    }
  }

  int infoCount(const ros::Time& t) {
    std::lock_guard<std::mutex> lock(mutex_);
    return info_counts_[t];
  }

  ros::NodeHandle nh_, pnh_;
  std::string depth_encoding_, color_encoding_, camera_frame_, odom_frame_, base_frame_;
  bool approx_ = true, exact_stamps_ = false;
  bool late_base_tf_ = false;  // the .test publishes no base transform: the test sends it
  std::string guess_frame_;    // the nodelet's guess_frame_id, when the .test sets one
  bool binned_ = false;        // camera_info with binning and a K unlike P
  std::string depth_frame_;    // the depth images' frame_id
  bool bad_params_ = false;    // the .test gives the nodelet a bad and an unknown parameter
  bool burst_ = false;         // a fresh nodelet for the burst test (stamps on the wall clock)
  // The nodelet's initial_pose, when the .test sets one ("x y z roll pitch yaw").
  std::optional<Eigen::Isometry3d> initial_pose_;
  Eigen::Isometry3d base_from_camera_;
  ros::Publisher rgb_pub_, depth_pub_, info_pub_;
  ros::Subscriber odom_sub_, info_sub_, diag_sub_, rosout_sub_;
  ros::ServiceClient reset_, reset_to_pose_;

 private:
  void onOdom(const nav_msgs::Odometry& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    odoms_[m.header.stamp] = m;
  }
  void onInfo(const acvo::OdometryInfo& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    infos_[m.header.stamp] = m;
    ++info_counts_[m.header.stamp];
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray& a) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : a.status) {
      if (s.name.find("odometry") != std::string::npos) {
        last_diag_ = s;
        last_diag_wall_ = ros::WallTime::now();
      }
    }
  }
  void onLog(const rosgraph_msgs::Log& m) {
    if (m.level < rosgraph_msgs::Log::WARN) return;
    std::lock_guard<std::mutex> lock(mutex_);
    logs_.emplace_back(ros::WallTime::now(), m.msg);
  }
  std::optional<acvo::OdometryInfo> infoAt(const ros::Time& t) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = infos_.find(t);
    if (it == infos_.end()) return std::nullopt;
    return it->second;
  }
  std::optional<nav_msgs::Odometry> odomAt(const ros::Time& t) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = odoms_.find(t);
    if (it == odoms_.end()) return std::nullopt;
    return it->second;
  }

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::mutex mutex_;
  std::map<ros::Time, nav_msgs::Odometry> odoms_;
  std::map<ros::Time, acvo::OdometryInfo> infos_;
  std::map<ros::Time, int> info_counts_;
  std::vector<std::pair<ros::WallTime, std::string>> logs_;  // warnings and errors on /rosout
  std::optional<diagnostic_msgs::DiagnosticStatus> last_diag_;
  ros::WallTime last_diag_wall_;
  std::map<int, RgbdImage> frames_;
  ros::Time next_stamp_;
};

Client* client = nullptr;

std::vector<int> range(int from, int to) {
  std::vector<int> v;
  for (int k = from; k < to; ++k) v.push_back(k);
  return v;
}

// A figure within kMargin of what was measured there (`measured`): fails otherwise, and prints
// "[ BOUND ] what: figure unit (bound < B)" for scripts/measure_ros_bounds.
void expectMeasured(const std::string& what, double figure, double measured, const char* unit) {
  const double bound = kMargin * measured;
  EXPECT_LT(figure, bound) << what << ": " << figure << " " << unit;
  std::cout << "[ BOUND ] " << what << ": " << figure << " " << unit << " (bound < " << bound
            << ")\n";
}

// A timing figure (or a count of frames that a backlog would raise) against a bound that is no
// multiple of a measurement: `catches` says what it is there to catch. Printed as "[ TIMING ]
// what: figure unit (bound OP B; catches ...)" for scripts/measure_ros_bounds.
void expectTiming(const std::string& what, double figure, const char* op, double bound,
                  const char* unit, const std::string& catches) {
  const bool within = std::string(op) == "<=" ? figure <= bound : figure < bound;
  EXPECT_TRUE(within) << what << ": " << figure << " " << unit << ", bound " << op << " " << bound
                      << " (catches " << catches << ")";
  std::cout << "[ TIMING ] " << what << ": " << figure << " " << unit << " (bound " << op << " "
            << bound << "; catches " << catches << ")\n";
}

// Within kMargin of what was measured there (`measured`), or exact (kExactPose).
void expectPoseNear(const geometry_msgs::Pose& got, const Eigen::Isometry3d& want,
                    const Measured& measured, const std::string& what) {
  const Eigen::Isometry3d g = toEigen(got);
  const double dt = (g.translation() - want.translation()).norm();
  const double dr = angleOf(g.rotation().transpose() * want.rotation());
  if (measured.t > 0.0) {
    expectMeasured(what + ", translation error", dt, measured.t, "m");
    expectMeasured(what + ", rotation error", dr, measured.r, "rad");
    return;
  }
  EXPECT_LT(dt, kExact) << what << ": translation error " << dt << " m";
  EXPECT_LT(dr, kExact) << what << ": rotation error " << dr << " rad";
  std::cout << "[ MEASURED ] " << what << " (exact): translation error " << dt
            << " m, rotation error " << dr << " rad\n";
}

// Runs first (gtest keeps the order of definition): before any frame, the camera frame and its
// transform to the base are unknown; the pose given is where the first frame starts.
TEST(OdometryNodelet, AResetToPoseBeforeTheFirstFrameIsWhereItStarts) {
  if (client->late_base_tf_ || client->initial_pose_) {
    GTEST_SKIP() << "needs a nodelet that has seen no frame and starts at the origin";
  }
  Eigen::Isometry3d given = Eigen::Isometry3d::Identity();
  given.linear() = Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitZ()).matrix();
  given.translation() << -1.5, 0.25, 0.1;
  const auto res = client->resetTo(given);
  ASSERT_TRUE(res);
  EXPECT_TRUE(res->success) << res->message;
  std::cout << "[ MEASURED ] reset_odom_to_pose before the first frame: " << res->message << "\n";
  const std::vector<Outcome> out = client->run(range(0, 4));
  ASSERT_TRUE(out[0].odom && out.back().odom);
  EXPECT_EQ(out[0].info->tracking, "first_frame");
  expectPoseNear(out[0].odom->pose.pose, given, kExactPose, "first frame after an early reset_odom_to_pose");
  expectPoseNear(out.back().odom->pose.pose, given * client->expectedBase(cameraPose(3)), Measured{0.0000216, 0.00000697},
                 "3 frames after an early reset_odom_to_pose");
}

// initial_pose (nodelet_initial_pose.test): the first frame's pose, and tracking goes on from it.
TEST(OdometryNodelet, StartsAtTheInitialPose) {
  if (!client->initial_pose_) GTEST_SKIP() << "needs a .test that sets initial_pose";
  ASSERT_TRUE(client->tfFromAnotherNode());
  const std::vector<Outcome> out = client->run(range(0, 4));
  ASSERT_TRUE(out[0].odom && out.back().odom);
  EXPECT_EQ(out[0].info->tracking, "first_frame");
  expectPoseNear(out[0].odom->pose.pose, *client->initial_pose_, kExactPose, "first frame, initial_pose");
  expectPoseNear(out.back().odom->pose.pose,
                 *client->initial_pose_ * client->expectedBase(cameraPose(3)), Measured{0.00000345, 0.00000606},
                 "3 frames after initial_pose");
  const auto tf = client->lookup(out.back().odom->header.stamp);
  ASSERT_TRUE(tf);
  EXPECT_TRUE(tf2::transformToEigen(*tf).isApprox(toEigen(out.back().odom->pose.pose), 1e-6));
  // reset_odom goes back to the origin, not to initial_pose (as rtabmap's).
  ASSERT_TRUE(client->reset());
  const std::vector<Outcome> again = client->run(range(4, 6));
  ASSERT_TRUE(again[0].odom);
  expectPoseNear(again[0].odom->pose.pose, Eigen::Isometry3d::Identity(), kExactPose, "after reset_odom");
}

TEST(OdometryNodelet, TracksKnownMotionWithRightFramesCovarianceAndTf) {
  ASSERT_TRUE(client->reset());
  std::vector<ros::Time> stamps;
  const std::vector<Outcome> out = client->run(range(0, kTrackFrames), &stamps);
  ASSERT_EQ(out.size(), static_cast<std::size_t>(kTrackFrames));
  double keyframe_variance = 0.0;  // the pose variance of the keyframe in use
  int keyframes = 0;
  double worst_twist = 0.0;  // m/s off the true velocity
  for (int k = 0; k < kTrackFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    ASSERT_TRUE(out[k].info) << "no odom_info";
    ASSERT_TRUE(out[k].odom) << "no odom (tracking " << out[k].info->tracking << ": "
                             << out[k].info->message << ")";
    const acvo::OdometryInfo& info = *out[k].info;
    const nav_msgs::Odometry& odom = *out[k].odom;
    EXPECT_TRUE(k == 0 ? info.tracking == "first_frame" : isTracking(info.tracking))
        << info.tracking << ": " << info.message << " (ell " << info.ell << ", "
        << info.iterations << " iterations)";
    EXPECT_FALSE(info.lost);
    // The default engine's own figures, by name; none of the paper engine's. The first frame
    // is registered to nothing and has none.
    std::vector<std::string> figures;
    for (const auto& f : info.engine_figures) figures.push_back(f.key);
    const std::vector<std::string> expected{"brightness_gain", "vignetting", "dense_weight"};
    EXPECT_EQ(figures, k == 0 ? std::vector<std::string>{} : expected);
    EXPECT_EQ(odom.header.frame_id, client->odom_frame_);
    EXPECT_EQ(odom.child_frame_id, client->base_frame_);
    EXPECT_EQ(info.header.frame_id, acvo_ros::stripSlash(client->camera_frame_));
    EXPECT_GT(info.moving_points, 100u);
    EXPECT_GT(info.ms_total, 0.0);
    // Pose covariance: never zero, below "lost"; the keyframe's plus one registration's, so
    // above the keyframe's (a random walk over keyframes, not frames).
    for (int d = 0; d < 6; ++d) EXPECT_GT(odom.pose.covariance[7 * d], 0.0);
    const double variance =
        odom.pose.covariance[0] + odom.pose.covariance[7] + odom.pose.covariance[14];
    if (k > 0) {
      EXPECT_GT(info.iterations, 0);
      EXPECT_GT(info.fixed_points, 100u);
      EXPECT_GT(variance, keyframe_variance);
      EXPECT_LT(variance, acvo_ros::kLostVariance);
      for (int d = 0; d < 6; ++d) EXPECT_GT(odom.twist.covariance[7 * d], 0.0);
      // Twist: the base-frame motion of one frame over 0.1 s. One registration is less exact
      // than the drift per frame suggests (errors partly cancel along the path).
      const Eigen::Isometry3d step = client->expectedBase(acvo_test::frameMotion());
      Eigen::Vector3d v(odom.twist.twist.linear.x, odom.twist.twist.linear.y,
                        odom.twist.twist.linear.z);
      worst_twist = std::max(worst_twist, (v - step.translation() / 0.1).norm());
    }
    if (info.new_keyframe) {
      keyframe_variance = variance;
      ++keyframes;
    }
  }
  EXPECT_GT(keyframes, 1) << "the camera moves on: the keyframe changes";
  expectMeasured("twist of a tracked frame, worst off the true velocity", worst_twist,
                 kTwistMeasured, "m/s");
  expectPoseNear(out.back().odom->pose.pose, client->expectedBase(cameraPose(kTrackFrames - 1)),
                 Measured{0.0000475, 0.0000203}, "final pose");

  const auto tf = client->lookup(stamps.back());
  ASSERT_TRUE(tf) << client->odom_frame_ << " -> " << client->base_frame_ << " not in TF";
  const Eigen::Isometry3d tf_pose = tf2::transformToEigen(*tf);
  EXPECT_TRUE(tf_pose.isApprox(toEigen(out.back().odom->pose.pose), 1e-6));

  const auto [level, message] = diagnosticFor(out.back().info->tracking);
  const auto diag = client->waitDiagnostic(level, message);
  ASSERT_TRUE(diag);
  EXPECT_EQ(diag->level, level) << diag->message;
  EXPECT_EQ(diag->message, message);
}

// The test camera's intrinsics are nominal (equal focal lengths about a 320x240 image's
// centre, no distortion): the diagnostics say what is in use and where it comes from, and the
// log warns once, at the first frame, that a real camera with these wants calibrating.
TEST(OdometryNodelet, TheIntrinsicsInUseAreSaidAndNominalOnesWarnedOnce) {
  ASSERT_TRUE(client->reset());
  client->run(range(0, 3));
  const auto said = client->diagnosticValueOnce(
      "camera intrinsics", [](const std::string& v) { return v != "none yet"; });
  ASSERT_TRUE(said);
  EXPECT_EQ(said->rfind("fx 262.5, fy 262.5, cx 159.5, cy 119.5 (320x240) from camera_info on ",
                        0),
            0u)
      << *said;
  EXPECT_NE(said->find("cam/info; nominal, not a calibration"), std::string::npos) << *said;
  const auto warning = client->waitLog("camera intrinsics: fx 262.5", ros::WallTime());
  ASSERT_TRUE(warning) << "no warning about the nominal intrinsics";
  EXPECT_NE(warning->find("camera_calibration"), std::string::npos) << *warning;
  EXPECT_EQ(client->countLogs("camera intrinsics:"), 1u) << "the same intrinsics told again";
}

TEST(OdometryNodelet, CloudIsPublishedToASubscriberInTheCameraFrame) {
  ASSERT_TRUE(client->reset());
  std::mutex m;
  std::vector<sensor_msgs::PointCloud2> clouds;
  ros::Subscriber sub = client->nh_.subscribe<sensor_msgs::PointCloud2>(
      "cloud", 10, [&](const sensor_msgs::PointCloud2ConstPtr& c) {
        std::lock_guard<std::mutex> lock(m);
        clouds.push_back(*c);
      });
  for (int i = 0; i < 200 && sub.getNumPublishers() == 0; ++i) ros::WallDuration(0.05).sleep();
  ASSERT_GT(sub.getNumPublishers(), 0u);
  ros::WallDuration(0.3).sleep();  // the publisher's side of the connection
  std::vector<ros::Time> stamps;
  const std::vector<Outcome> out = client->run({0, 1, 2}, &stamps);
  ros::WallDuration(0.5).sleep();
  std::lock_guard<std::mutex> lock(m);
  ASSERT_EQ(clouds.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(clouds[i].header.stamp, stamps[i]);
    EXPECT_EQ(clouds[i].header.frame_id, acvo_ros::stripSlash(client->camera_frame_));
    ASSERT_TRUE(out[i].info);
    EXPECT_EQ(clouds[i].width, out[i].info->moving_points);
  }
  // Read back as a PCL user would: every point in front of the camera within the room's depth,
  // its labels those of a colour image (HSV in [0, 1], gradients in [-1, 1]), and not all alike.
  pcl::PointCloud<acvo_ros::LabelledPoint> pc;
  pcl::fromROSMsg(clouds[0], pc);
  ASSERT_EQ(pc.size(), std::size_t{clouds[0].width});
  ASSERT_GT(pc.size(), 100u);
  float min_hue = 1.f, max_hue = 0.f, max_gradient = 0.f;
  for (const auto& p : pc) {
    EXPECT_GT(p.z, 0.5f);
    EXPECT_LT(p.z, 6.0f);
    for (float v : {p.hue, p.saturation, p.value}) {
      EXPECT_GE(v, 0.f);
      EXPECT_LE(v, 1.f);
    }
    EXPECT_LE(std::abs(p.gradient_x), 1.f);
    EXPECT_LE(std::abs(p.gradient_y), 1.f);
    min_hue = std::min(min_hue, p.hue);
    max_hue = std::max(max_hue, p.hue);
    max_gradient = std::max({max_gradient, std::abs(p.gradient_x), std::abs(p.gradient_y)});
  }
  EXPECT_LT(min_hue, max_hue) << "labels carry the image's colours";
  EXPECT_GT(max_gradient, 0.f) << "selected points sit on intensity gradients";
  pcl::PointCloud<pcl::PointXYZRGB> rgb;
  pcl::fromROSMsg(clouds[0], rgb);
  ASSERT_EQ(rgb.size(), pc.size());
  EXPECT_EQ(rgb[0].rgb, pc[0].rgb);
}

TEST(OdometryNodelet, ResetReturnsToIdentityAndToAGivenPose) {
  ASSERT_TRUE(client->reset());
  client->run(range(0, 4));
  ASSERT_TRUE(client->reset());
  std::vector<Outcome> out = client->run(range(4, 8));
  ASSERT_TRUE(out[0].odom && out.back().odom);
  EXPECT_EQ(out[0].info->tracking, "first_frame");
  expectPoseNear(out[0].odom->pose.pose, Eigen::Isometry3d::Identity(), kExactPose, "after reset_odom");
  expectPoseNear(out.back().odom->pose.pose,
                 client->expectedBase(cameraPose(4).inverse() * cameraPose(7)), Measured{0.0000103, 0.00000903},
                 "3 frames after reset_odom");

  Eigen::Isometry3d given = Eigen::Isometry3d::Identity();
  given.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).matrix();
  given.translation() << 1.0, -2.0, 0.5;
  const auto res = client->resetTo(given);
  ASSERT_TRUE(res);
  EXPECT_TRUE(res->success) << res->message;
  out = client->run(range(8, 12));
  ASSERT_TRUE(out[0].odom && out.back().odom);
  expectPoseNear(out[0].odom->pose.pose, given, kExactPose, "after reset_odom_to_pose");
  expectPoseNear(out.back().odom->pose.pose,
                 given * client->expectedBase(cameraPose(8).inverse() * cameraPose(11)), Measured{0.0000117, 0.0000106},
                 "3 frames after reset_odom_to_pose");

  geometry_msgs::Pose bad;  // zero quaternion
  acvo::ResetToPose srv;
  srv.request.pose = bad;
  ASSERT_TRUE(client->reset_to_pose_.call(srv));
  EXPECT_FALSE(srv.response.success);
}

TEST(OdometryNodelet, InvalidFramesAreLostThenTrackingResumes) {
  ASSERT_TRUE(client->reset());
  std::vector<Outcome> good = client->run(range(0, 4));
  ASSERT_TRUE(good.back().odom);
  const geometry_msgs::Pose held = good.back().odom->pose.pose;
  const double held_variance = good.back().odom->pose.covariance[0];
  const std::uint32_t lost_before = good.back().info->lost_count;

  // Depth all invalid (0 mm in 16UC1, NaN in 32FC1), depth all beyond the range, then a
  // featureless grey image with valid depth: each lost, the message names the cause.
  const std::vector<std::pair<RgbdImage, std::string>> invalid = {
      {client->blank(), "no valid depth"},
      {client->farDepth(4), "no valid depth"},
      {client->flatColour(4), "no intensity gradient"}};
  // One frame in flight at a time (run()): the subscriber queues are short by design.
  std::vector<RgbdImage> images;
  std::vector<ros::Time> stamps;
  for (const auto& frame : invalid) {
    images.push_back(frame.first);
    stamps.push_back(client->nextStamp());
  }
  const std::vector<Outcome> outcomes = client->run(images, stamps);
  for (std::size_t i = 0; i < invalid.size(); ++i) {
    SCOPED_TRACE(invalid[i].second);
    const Outcome& o = outcomes[i];
    ASSERT_TRUE(o.info);
    EXPECT_TRUE(o.info->lost) << o.info->tracking << ": " << o.info->message;
    EXPECT_EQ(o.info->tracking, "lost");
    EXPECT_NE(o.info->message.find(invalid[i].second), std::string::npos) << o.info->message;
    ASSERT_TRUE(o.odom) << "publish_null_when_lost is false: the held pose is published";
    // The held pose may be wrong by what the camera can move unseen: its covariance grows but
    // stays meaningful for a filter; the velocity is unknown.
    EXPECT_GT(o.odom->pose.covariance[0], held_variance);
    EXPECT_LT(o.odom->pose.covariance[0], acvo_ros::kLostVariance);
    EXPECT_GE(o.odom->twist.covariance[35], acvo_ros::kLostVariance);
    expectPoseNear(o.odom->pose.pose, toEigen(held), kExactPose, "held pose while lost");
    if (i + 1 == invalid.size()) {
      EXPECT_EQ(o.info->lost_count, lost_before + invalid.size());
    }
  }
  const auto diag = client->waitDiagnostic(diagnostic_msgs::DiagnosticStatus::ERROR, "lost");
  ASSERT_TRUE(diag);
  EXPECT_EQ(diag->level, diagnostic_msgs::DiagnosticStatus::ERROR);
  EXPECT_EQ(diag->message, "lost");

  // The node still answers and tracks again from good frames (the reference re-seeds from the
  // first good frame, so the motion from there on is measured again).
  std::vector<Outcome> again = client->run(range(5, 9));
  ASSERT_TRUE(again.back().info);
  EXPECT_FALSE(again.back().info->lost) << again.back().info->message;
  EXPECT_TRUE(isTracking(again.back().info->tracking)) << again.back().info->tracking;
  ASSERT_TRUE(again[0].odom && again.back().odom);
  const Eigen::Isometry3d since =
      toEigen(again[0].odom->pose.pose).inverse() * toEigen(again.back().odom->pose.pose);
  const Eigen::Isometry3d want = client->expectedBase(cameraPose(5).inverse() * cameraPose(8));
  const double since_t = (since.translation() - want.translation()).norm();
  expectMeasured("3 frames after invalid ones, translation error", since_t,
                 kAfterInvalidMeasured, "m");
  const auto [level, message] = diagnosticFor(again.back().info->tracking);
  const auto ok = client->waitDiagnostic(level, message);
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->message, message);
}

// Expected pose of frame k relative to frame j, published in the base frame.
Eigen::Isometry3d expectedMotion(int j, int k) {
  return client->expectedBase(cameraPose(j).inverse() * cameraPose(k));
}

Eigen::Isometry3d relativePose(const Outcome& from, const Outcome& to) {
  return toEigen(from.odom->pose.pose).inverse() * toEigen(to.odom->pose.pose);
}

TEST(OdometryNodelet, EveryOtherFrameMissingIsTrackedAndEveryFrameIsPublished) {
  ASSERT_TRUE(client->reset());
  // Frames 0, 2, ..., 12 with their stamps: the stamp of each missing frame is skipped, so
  // each registration spans 0.2 s and twice the motion of a frame (3 cm, 1.2 deg).
  constexpr int kLast = 12;
  std::vector<RgbdImage> images;
  std::vector<ros::Time> stamps;
  for (int k = 0; k <= kLast; k += 2) {
    if (k > 0) client->nextStamp();  // the missing frame's
    images.push_back(client->frame(k));
    stamps.push_back(client->nextStamp());
  }
  const std::vector<Outcome> out = client->run(images, stamps);
  ASSERT_EQ(out.size(), images.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(2 * i));
    ASSERT_TRUE(out[i].info) << "no odom_info";
    ASSERT_TRUE(out[i].odom) << "no odom (" << out[i].info->tracking << ": " << out[i].info->message
                             << ")";
    EXPECT_TRUE(i == 0 ? out[i].info->tracking == "first_frame" : isTracking(out[i].info->tracking))
        << out[i].info->tracking << ": " << out[i].info->message;
  }
  // The budget is per frame of motion (12 frames' worth in 6 registrations).
  expectPoseNear(out.back().odom->pose.pose, client->expectedBase(cameraPose(kLast)),
                 Measured{0.0000320, 0.0000132}, "every other frame missing, final pose");
}

// One second of blank frames at 10 Hz while the camera moves on (frames 4-13: 15 cm, 6 deg),
// the first half without valid depth, the second half of one colour; then good frames again.
TEST(OdometryNodelet, BlackoutOfBlankFramesIsLostNamedThenTrackingResumes) {
  ASSERT_TRUE(client->reset());
  constexpr int kBefore = 4, kBlank = 10, kAfter = 8;
  std::vector<RgbdImage> images;
  std::vector<ros::Time> stamps;
  for (int k = 0; k < kBefore + kBlank + kAfter; ++k) {
    const bool blank = k >= kBefore && k < kBefore + kBlank;
    images.push_back(!blank                     ? client->frame(k)
                     : k < kBefore + kBlank / 2 ? client->blank()
                                                : client->flatColour(k));
    stamps.push_back(client->nextStamp());
  }
  const std::vector<Outcome> out = client->run(images, stamps);
  ASSERT_EQ(out.size(), images.size());
  for (const Outcome& o : out) {
    ASSERT_TRUE(o.info && o.odom) << "every frame gets odom_info and odom (held while lost)";
    EXPECT_TRUE(toEigen(o.odom->pose.pose).matrix().allFinite());
  }
  for (int k = 1; k < kBefore; ++k) EXPECT_TRUE(isTracking(out[k].info->tracking)) << k;
  const geometry_msgs::Pose held = out[kBefore - 1].odom->pose.pose;
  for (int k = kBefore; k < kBefore + kBlank; ++k) {
    SCOPED_TRACE("blank frame " + std::to_string(k));
    EXPECT_TRUE(out[k].info->lost);
    const std::string cause = k < kBefore + kBlank / 2 ? "no valid depth" : "no intensity gradient";
    EXPECT_NE(out[k].info->message.find(cause), std::string::npos) << out[k].info->message;
    EXPECT_TRUE(toEigen(out[k].odom->pose.pose).isApprox(toEigen(held), kExact));
    // Grows with the time unseen (odometry.lost_speed 1 m/s: (0.1 m)^2 per 0.1 s frame and
    // more), stays below "do not trust this" and keeps a filter's use of the pose.
    // Stamps become seconds since 1970 in a double, resolved to 2.4e-7 s: the time unseen is 0.1 s
    // to a few 1e-6 of itself, and the last tracked frame's own variance (about 1e-10 m^2 with
    // the direct terms) no longer hides that.
    const double variance = out[k].odom->pose.covariance[0];
    const double unseen = 0.1 * (k - kBefore + 1);
    EXPECT_GE(variance, unseen * unseen * (1.0 - 1e-5));
    EXPECT_GT(variance, out[k - 1].odom->pose.covariance[0]);
    EXPECT_LT(variance, acvo_ros::kLostVariance);
    EXPECT_GE(out[k].odom->twist.covariance[0], acvo_ros::kLostVariance);
  }
  // TF goes on through the blackout, at the held pose (no guess here).
  for (int k = kBefore; k < kBefore + kBlank; ++k) {
    const auto tf = client->lookup(stamps[k]);
    ASSERT_TRUE(tf) << "no TF at blank frame " << k;
    EXPECT_TRUE(tf2::transformToEigen(*tf).isApprox(toEigen(held), 1e-6)) << k;
  }
  // Tracking resumes within two frames of the blackout's end and stays.
  int resumed = kBefore + kBlank;
  while (resumed < int(out.size()) && !isTracking(out[resumed].info->tracking)) ++resumed;
  for (int k = kBefore + kBlank; k < int(out.size()); ++k) {
    std::cout << "[ MEASURED ] after the blackout, frame " << k << ": " << out[k].info->tracking
              << " " << out[k].info->message << "\n";
  }
  EXPECT_LE(resumed, kBefore + kBlank + 1);
  for (int k = resumed; k < int(out.size()); ++k) {
    EXPECT_TRUE(isTracking(out[k].info->tracking))
        << "frame " << k << ": " << out[k].info->tracking << " " << out[k].info->message;
  }
  const int last = int(out.size()) - 1;
  ASSERT_LT(resumed, last);
  // From resumption on, the motion is measured as usual.
  const Eigen::Isometry3d since = relativePose(out[resumed], out[last]);
  const Eigen::Isometry3d want = expectedMotion(resumed, last);
  const double since_t = (since.translation() - want.translation()).norm();
  const double since_r = angleOf(since.rotation().transpose() * want.rotation());
  std::cout << "[ MEASURED ] blackout: resumed at frame " << resumed << "; from there to frame "
            << last << ": translation error " << since_t << " m, rotation error " << since_r
            << " rad\n";
  expectMeasured("blackout, from resumption on, translation error", since_t,
                 kAfterBlackoutMeasured.t, "m");
  expectMeasured("blackout, from resumption on, rotation error", since_r,
                 kAfterBlackoutMeasured.r, "rad");
  // No jump on recovery (REP 105: odom is continuous), not by the 17 cm the camera travelled
  // unseen: where the frame after the blackout registers again against the last frame before it
  // (both configurations today: the unseen motion found to micrometres), the published pose goes
  // on from the held one exactly, as dead reckoning without a guess has it (ContinuousOdom);
  // where that frame was lost and became the reference (the 16-bit camera before the direct
  // terms), the frame that tracks again moves the published pose by one frame's motion.
  const bool bridged = resumed == kBefore + kBlank;
  const Eigen::Isometry3d step = toEigen(out[resumed - 1].odom->pose.pose).inverse() *
                                 toEigen(out[resumed].odom->pose.pose);
  const Eigen::Isometry3d one =
      bridged ? Eigen::Isometry3d::Identity() : expectedMotion(resumed - 1, resumed);
  const double step_t = (step.translation() - one.translation()).norm();
  const double step_r = angleOf(step.rotation().transpose() * one.rotation());
  std::cout << "[ MEASURED ] blackout without a guess: recovery moves the published pose by "
            << step.translation().norm() << " m, " << step_t << " m off "
            << (bridged ? "the held pose" : "one frame's motion") << ", " << step_r << " rad\n";
  EXPECT_TRUE(toEigen(out[resumed - 1].odom->pose.pose).isApprox(toEigen(held), kExact));
  if (bridged) {
    EXPECT_LT(step_t, kExact) << "the recovery moved the published pose";
    EXPECT_LT(step_r, kExact) << "the recovery turned the published pose";
  } else {
    // No configuration takes this branch today: its figures are those measured when the 16-bit
    // one did (0.134 mm, 0.078 mrad), at the drift of the frames after it.
    EXPECT_LT(step_t, kMargin * kAfterBlackoutMeasured.t + 0.000134) << "m";
    EXPECT_LT(step_r, kMargin * kAfterBlackoutMeasured.r + 0.000078) << "rad";
  }
  // Across the blackout: the motion during it is not observed (the pose is held while lost,
  // and the recovery does not jump); the error is that motion plus the registered frames'
  // drift.
  const Eigen::Isometry3d across = relativePose(out[kBefore - 1], out[last]);
  const Eigen::Isometry3d truth = expectedMotion(kBefore - 1, last);
  const Eigen::Isometry3d unseen = expectedMotion(kBefore - 1, resumed);
  const double across_t = (across.translation() - truth.translation()).norm();
  std::cout << "[ MEASURED ] blackout: error from frame " << kBefore - 1 << " to " << last << ": "
            << across_t << " m (motion from the last good frame to resumption "
            << unseen.translation().norm() << " m)\n";
  // The registered frames' drift as measured from resumption (above).
  EXPECT_LT(across_t, unseen.translation().norm() + kMargin * kAfterBlackoutMeasured.t);
}

// The same blackout with wheel odometry on TF (guess_frame_id): while lost, the base follows
// the wheels in the odom frame (TF odom -> wheels stays, wheels -> base moves on), the odometry
// message dead-reckons on them, and the recovery goes on from there without a jump.
TEST(OdometryNodelet, WithAGuessTheBlackoutFollowsTheWheelsAndRecoversWithoutAJump) {
  if (client->guess_frame_.empty()) GTEST_SKIP() << "needs nodelet_guess.test";
  ASSERT_TRUE(client->reset());
  constexpr int kBefore = 4, kBlank = 6, kAfter = 6;
  std::vector<RgbdImage> images;
  std::vector<ros::Time> stamps;
  std::vector<Eigen::Isometry3d> wheels;
  for (int k = 0; k < kBefore + kBlank + kAfter; ++k) {
    const bool blank = k >= kBefore && k < kBefore + kBlank;
    images.push_back(blank ? client->blank() : client->frame(k));
    stamps.push_back(client->nextStamp());
    wheels.push_back(client->expectedBase(cameraPose(k)));
  }
  const std::vector<Outcome> out = client->run(images, stamps, wheels);
  ASSERT_EQ(out.size(), images.size());
  for (const Outcome& o : out) ASSERT_TRUE(o.info && o.odom);
  for (int k = 1; k < kBefore; ++k) ASSERT_TRUE(isTracking(out[k].info->tracking)) << k;
  // The odom frame's origin is the first frame's base pose (the wheels' at frame 0).
  const Eigen::Isometry3d origin = wheels[0];
  for (int k = kBefore; k < kBefore + kBlank; ++k) {
    SCOPED_TRACE("blank frame " + std::to_string(k));
    EXPECT_TRUE(out[k].info->lost);
    EXPECT_TRUE(out[k].info->guess_from_tf);
    // Dead-reckoned on the wheels from the last tracked frame: off by that frame's drift only.
    const Eigen::Isometry3d want = origin.inverse() * wheels[k];
    expectPoseNear(out[k].odom->pose.pose, want, Measured{0.000000849, 0.00000181}, "lost, on the wheels");
    const auto tf = client->lookup(stamps[k]);
    ASSERT_TRUE(tf) << "no TF odom -> base through the wheels while lost";
    EXPECT_TRUE(tf2::transformToEigen(*tf).isApprox(toEigen(out[k].odom->pose.pose), 1e-6));
  }
  int resumed = kBefore + kBlank;
  while (resumed < int(out.size()) && !isTracking(out[resumed].info->tracking)) ++resumed;
  ASSERT_LE(resumed, kBefore + kBlank + 1);
  // No jump: the recovery is one frame's motion on from the last lost frame.
  const Eigen::Isometry3d step =
      toEigen(out[resumed - 1].odom->pose.pose).inverse() * toEigen(out[resumed].odom->pose.pose);
  const Eigen::Isometry3d true_step = wheels[resumed - 1].inverse() * wheels[resumed];
  std::cout << "[ MEASURED ] blackout with a guess: recovery step off the true one by "
            << (step.translation() - true_step.translation()).norm() << " m\n";
  // The guess's own step, exactly but for rounding (the recovery continues from the wheels:
  // 7e-17 m measured).
  EXPECT_LT((step.translation() - true_step.translation()).norm(), 1e-6);
  // And the whole run is where the wheels say: nothing of the blackout's motion is lost.
  const int last = int(out.size()) - 1;
  expectPoseNear(out[last].odom->pose.pose, origin.inverse() * wheels[last],
                 Measured{0.00000264, 0.00000068}, "end of a blackout bridged by the wheels");
}

// One frame of noise (random colour and depth) inside a sequence.
TEST(OdometryNodelet, ASingleFrameOfNoiseIsLostAndTrackingResumes) {
  ASSERT_TRUE(client->reset());
  std::vector<RgbdImage> images = {client->frame(0), client->frame(1), client->frame(2),
                                   client->noise(7), client->frame(4), client->frame(5),
                                   client->frame(6)};
  std::vector<ros::Time> stamps;
  for (std::size_t i = 0; i < images.size(); ++i) stamps.push_back(client->nextStamp());
  const std::vector<Outcome> out = client->run(images, stamps);
  for (const Outcome& o : out) ASSERT_TRUE(o.info && o.odom);
  EXPECT_TRUE(out[3].info->lost) << out[3].info->tracking << ": " << out[3].info->message;
  EXPECT_FALSE(out[3].info->message.empty());
  for (std::size_t k = 4; k < out.size(); ++k) {
    std::cout << "[ MEASURED ] after the noise frame, frame " << k << ": " << out[k].info->tracking
              << " " << out[k].info->message << "\n";
  }
  EXPECT_TRUE(isTracking(out[5].info->tracking)) << out[5].info->message;
  EXPECT_TRUE(isTracking(out[6].info->tracking)) << out[6].info->message;
  // Frame 4 is registered against frame 2 (the noise frame did not replace the reference): its
  // motion spans 0.2 s, and the twist divides it by that, not by the 0.1 s since frame 3.
  ASSERT_TRUE(isTracking(out[4].info->tracking)) << out[4].info->message;
  const Eigen::Isometry3d step = client->expectedBase(acvo_test::frameMotion());
  const auto& twist = out[4].odom->twist.twist.linear;
  const Eigen::Vector3d v(twist.x, twist.y, twist.z);
  expectMeasured("twist after the noise frame, off the true velocity",
                 (v - step.translation() / 0.1).norm(), kTwistAfterNoiseMeasured, "m/s");
  EXPECT_TRUE(toEigen(out.back().odom->pose.pose).matrix().allFinite());
}

// A pause of 3 s between two frames (max_time_gap 1 s): warned about, the frame after it is
// processed. The motion prior is one frame's motion (per frame, not per second), and the
// camera moved one frame's worth during the pause here: tracking goes on.
TEST(OdometryNodelet, ALargeStampGapIsWarnedAndProcessingContinues) {
  ASSERT_TRUE(client->reset());
  std::vector<Outcome> before = client->run(range(0, 4));
  ASSERT_TRUE(before.back().odom);
  const ros::WallTime since = ros::WallTime::now();
  client->skipTime(3.0);
  std::vector<Outcome> after = client->run(range(4, 7));
  for (const Outcome& o : after) {
    ASSERT_TRUE(o.info && o.odom) << "a frame after the gap was not published";
    EXPECT_TRUE(isTracking(o.info->tracking)) << o.info->tracking << ": " << o.info->message;
  }
  const auto warning = client->waitLog("between frames", since);
  ASSERT_TRUE(warning) << "no warning about the gap on /rosout";
  EXPECT_NE(warning->find("max_time_gap"), std::string::npos) << *warning;
  std::cout << "[ MEASURED ] gap warning: " << *warning << "\n";
  expectPoseNear(after.back().odom->pose.pose, client->expectedBase(cameraPose(6)), Measured{0.0000161, 0.0000143},
                 "3 frames after a 3 s gap");
}

TEST(OdometryNodelet, BadInputIsNamedAndSkippedAndTheNodeCarriesOn) {
  ASSERT_TRUE(client->reset());
  client->run(range(0, 3));
  struct Bad {
    std::string what;
    std::function<void(sensor_msgs::Image&, sensor_msgs::Image&, sensor_msgs::CameraInfo&)> spoil;
    std::string expected;  // in odom_info.message
  };
  const std::vector<Bad> cases = {
      {"depth encoding",
       [](auto&, auto& d, auto&) {
         d.encoding = "8UC1";
         d.step = d.width;
         d.data.resize(d.step * d.height);
       },
       "'8UC1'"},
      {"colour encoding", [](auto& c, auto&, auto&) { c.encoding = "bayer_rggb8"; },
       "'bayer_rggb8'"},
      {"truncated colour", [](auto& c, auto&, auto&) { c.data.resize(c.data.size() / 2); },
       "truncated"},
      {"short step", [](auto&, auto& d, auto&) { d.step = d.width; }, "step"},
      // A row that does not end on a whole element (cv::Mat would throw on it).
      {"odd step",
       [](auto&, auto& d, auto&) {
         d.step += 1;
         d.data.resize(std::size_t{d.step} * d.height);
       },
       "not a multiple"},
      {"size mismatch",
       [](auto&, auto& d, auto&) {
         d.width /= 2;
         d.step /= 2;
       },
       "differ in size"},
      // The projection matrix is what is used (K describes the raw image).
      {"zero focal length", [](auto&, auto&, auto& i) { i.P[0] = 0.0; }, "focal"},
      {"camera_info size", [](auto&, auto&, auto& i) { i.width = 640; }, "camera_info size"},
  };
  for (const Bad& bad : cases) {
    SCOPED_TRACE(bad.what);
    const ros::Time t = client->nextStamp();
    client->send(client->frame(3), t, bad.spoil);
    client->flush();
    const Outcome o = client->outcome(t, false);
    ASSERT_TRUE(o.info) << "no odom_info for a bad frame: node dead?";
    EXPECT_EQ(o.info->tracking, "bad_frame");
    EXPECT_NE(o.info->message.find(bad.expected), std::string::npos) << o.info->message;
    EXPECT_FALSE(o.odom) << "a bad frame must not be published";
    if (bad.what == "odd step") {
      // Diagnostics say it too (it once threw past the rejection path: no report at all).
      const auto d = client->waitDiagnostic(diagnostic_msgs::DiagnosticStatus::ERROR, "bad input");
      ASSERT_TRUE(d);
      EXPECT_EQ(d->message, "bad input");
      bool named = false;
      for (const auto& kv : d->values) {
        named = named || (kv.key == "last message" && kv.value.find("not a multiple") !=
                                                            std::string::npos);
      }
      EXPECT_TRUE(named) << "diagnostics do not name the misaligned step";
    }
  }
  // The topic is named for encoding problems.
  const ros::Time t = client->nextStamp();
  client->send(client->frame(3), t, [](auto&, auto& d, auto&) { d.encoding = "mono16x"; });
  client->flush();
  const Outcome named = client->outcome(t, false);
  ASSERT_TRUE(named.info);
  EXPECT_NE(named.info->message.find("cam/depth"), std::string::npos) << named.info->message;

  // Good frames go on from the last good one as if nothing happened.
  const std::vector<Outcome> out = client->run(range(3, 6));
  ASSERT_TRUE(out.back().odom);
  EXPECT_TRUE(isTracking(out.back().info->tracking)) << out.back().info->message;
  expectPoseNear(out.back().odom->pose.pose, client->expectedBase(cameraPose(5)), Measured{0.0000253, 0.0000123},
                 "after bad frames");
}

// A frame whose stamp is not after the last processed one is not processed, and goes the way of
// every frame that is not: odom_info says bad_frame and why, the log says it (throttled per
// cause), diagnostics count it. Before, such a frame left only a throttled log line.
TEST(OdometryNodelet, StampsRepeatedAreRejectedNamedAndAJumpBackKeepsThePose) {
  if (!client->exact_stamps_) {
    GTEST_SKIP() << "approximate sync drops reordered stamps itself; run with exact sync";
  }
  ASSERT_TRUE(client->reset());
  std::vector<ros::Time> stamps;
  client->run(range(0, 3), &stamps);
  const long rejected_before = std::stol(client->diagnosticValueAfter(
      "frames rejected", ros::WallTime::now()).value_or("-1000"));
  EXPECT_GE(rejected_before, 0) << "no \"frames rejected\" in diagnostics";
  // The same stamp again: rejected before it reaches the odometry (a second odom_info, which
  // says so).
  ASSERT_EQ(client->infoCount(stamps.back()), 1);
  const ros::WallTime since = ros::WallTime::now();
  client->send(client->frame(3), stamps.back());
  // A later frame shows the node still processes frames, and gives the repeat time to arrive.
  const ros::Time later = client->nextStamp();
  client->send(client->frame(3), later);
  ASSERT_TRUE(client->outcome(later, true).odom);
  ASSERT_EQ(client->infoCount(stamps.back()), 2) << "a repeated stamp went unreported";
  const Outcome repeat = client->outcome(stamps.back(), false);
  EXPECT_EQ(repeat.info->tracking, "bad_frame");
  EXPECT_NE(repeat.info->message.find("is not after the last processed frame's"),
            std::string::npos)
      << repeat.info->message;
  // A stamp a little before the last one (reordered): rejected too.
  const ros::Time earlier = later - ros::Duration(0.05);
  client->send(client->frame(4), earlier);
  const ros::Time after = client->nextStamp();
  client->send(client->frame(4), after);
  ASSERT_TRUE(client->outcome(after, true).odom);
  ASSERT_EQ(client->infoCount(earlier), 1) << "a stamp before the last one went unreported";
  const Outcome reordered = client->outcome(earlier, false);
  EXPECT_EQ(reordered.info->tracking, "bad_frame") << "a stamp before the last one was processed";
  EXPECT_NE(reordered.info->message.find("a repeated or reordered frame"), std::string::npos)
      << reordered.info->message;
  EXPECT_FALSE(reordered.odom);
  // The log says it (throttled per cause: once for the two), and diagnostics count both.
  const auto logged = client->waitLog("frame skipped: stamp ", since);
  ASSERT_TRUE(logged) << "no warning on /rosout";
  EXPECT_NE(logged->find("is not after the last processed frame's"), std::string::npos)
      << *logged;
  const auto rejected = client->diagnosticValueOnce("frames rejected", [&](const std::string& v) {
    return std::stol(v) >= rejected_before + 2;
  });
  ASSERT_TRUE(rejected);
  EXPECT_EQ(std::stol(*rejected), rejected_before + 2);
  const Outcome before = client->outcome(after, true);
  ASSERT_TRUE(before.odom);
  // A stamp 5 s in the past on a live clock (this test's stamps are the wall clock's): a
  // driver restarted, a clock stepped. The robot did not go back to the origin: the pose is
  // kept and tracking restarts from this frame. (Off the 0.1 s grid of the stamps sent so far,
  // so that its odom_info cannot be confused with an earlier frame's.)
  const ros::Time back = after - ros::Duration(5.05);
  const ros::WallTime before_jump = ros::WallTime::now();
  client->send(client->frame(4), back);
  const Outcome restarted = client->outcome(back, true);
  ASSERT_TRUE(restarted.info);
  EXPECT_EQ(restarted.info->tracking, "first_frame");
  ASSERT_TRUE(restarted.odom);
  expectPoseNear(restarted.odom->pose.pose, toEigen(before.odom->pose.pose), kExactPose,
                 "after a jump back on the live clock");
  EXPECT_TRUE(client->waitLog("pose is kept", before_jump)) << "no warning on /rosout";
  // A stream that starts again less than 1 s back (a short loop): the first frame behind is
  // dropped as out of order, the second (later than the first) restarts; nothing stalls.
  const ros::Time b1 = back + ros::Duration(0.1), b2 = back + ros::Duration(0.2);
  client->send(client->frame(5), b1);
  ASSERT_TRUE(client->outcome(b1, true).odom);
  client->send(client->frame(5), b2);
  const Outcome at_b2 = client->outcome(b2, true);
  ASSERT_TRUE(at_b2.odom);
  const ros::Time loop1 = back + ros::Duration(0.013), loop2 = back + ros::Duration(0.113);
  client->send(client->frame(4), loop1);
  client->send(client->frame(5), loop2);
  const Outcome looped = client->outcome(loop2, true);
  ASSERT_TRUE(looped.info) << "the looped stream stalled";
  const Outcome behind = client->outcome(loop1, false);
  ASSERT_TRUE(behind.info) << "the first frame behind went unreported";
  EXPECT_EQ(behind.info->tracking, "bad_frame") << "the first frame behind is dropped";
  EXPECT_EQ(looped.info->tracking, "first_frame");
  ASSERT_TRUE(looped.odom);
  expectPoseNear(looped.odom->pose.pose, toEigen(at_b2.odom->pose.pose), kExactPose, "after a short loop");
}

dynamic_reconfigure::Reconfigure::Response reconfigure(const std::string& name, double value,
                                                       bool is_int) {
  dynamic_reconfigure::Reconfigure srv;
  if (is_int) {
    dynamic_reconfigure::IntParameter p;
    p.name = name;
    p.value = static_cast<int>(value);
    srv.request.config.ints.push_back(p);
  } else {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name;
    p.value = value;
    srv.request.config.doubles.push_back(p);
  }
  EXPECT_TRUE(ros::service::call("acvo/set_parameters", srv)) << "acvo/set_parameters";
  return srv.response;
}

TEST(OdometryNodelet, ReconfigureRestartsTrackingWithNewParametersAndRefusesBadOnes) {
  ASSERT_TRUE(client->reset());
  std::vector<Outcome> before = client->run(range(0, 3));
  ASSERT_TRUE(before.back().odom);
  const std::uint32_t points = before.back().info->moving_points;
  ASSERT_GT(points, 1000u);  // target_points 3000 in test_params.yaml: 1500 at 320x240

  reconfigure("target_points", 500, true);
  std::vector<Outcome> after = client->run(range(3, 6));
  ASSERT_TRUE(after[0].odom && after.back().odom);
  EXPECT_EQ(after[0].info->tracking, "first_frame") << "a parameter change restarts tracking";
  expectPoseNear(after[0].odom->pose.pose, toEigen(before.back().odom->pose.pose), kExactPose,
                 "pose kept across a reconfigure");
  EXPECT_LT(after.back().info->moving_points, 700u);
  EXPECT_TRUE(isTracking(after.back().info->tracking)) << after.back().info->message;

  // ell_min above ell_max is refused: the odometry carries on with the previous parameters,
  // and the server reports the values in use.
  const auto refusal = reconfigure("ell_min", 0.5, false);
  bool reported = false;
  for (const auto& d : refusal.config.doubles) {
    if (d.name == "ell_min") {
      reported = true;
      EXPECT_DOUBLE_EQ(d.value, acvo::Params().coarse_to_fine.ell_min);
    }
  }
  EXPECT_TRUE(reported);
  std::vector<Outcome> refused = client->run(range(6, 8));
  ASSERT_TRUE(refused[0].info);
  EXPECT_TRUE(isTracking(refused[0].info->tracking)) << refused[0].info->tracking;
  EXPECT_LT(refused[0].info->moving_points, 700u);

  reconfigure("target_points", 3000, true);
}

// While lost with wheel odometry (guess_frame_id) the published pose dead-reckons on the wheels
// while the odometry holds the pose of its last tracked frame. A restart that keeps the pose (a
// parameter changed through dynamic_reconfigure; the live clock stepping back) starts the
// odometry again from that held pose: what is published must go on from the dead-reckoned pose,
// not snap back to the held one (it did: the correction was not updated on lost frames that did
// not become the reference).
TEST(OdometryNodelet, WithAGuessARestartWhileLostGoesOnFromTheDeadReckonedPose) {
  if (client->guess_frame_.empty()) GTEST_SKIP() << "needs nodelet_guess.test";
  ASSERT_TRUE(client->reset());
  std::vector<Eigen::Isometry3d> wheels;
  for (int k = 0; k < 12; ++k) wheels.push_back(client->expectedBase(cameraPose(k)));
  // Frames 0-3 tracked, then 4-6 blank: lost, on the wheels.
  const auto stretch = [&](int from, int to, int first_blank) {
    std::vector<RgbdImage> images;
    std::vector<ros::Time> stamps;
    std::vector<Eigen::Isometry3d> guesses;
    for (int k = from; k < to; ++k) {
      images.push_back(k >= first_blank ? client->blank() : client->frame(k));
      stamps.push_back(client->nextStamp());
      guesses.push_back(wheels[k]);
    }
    return client->run(images, stamps, guesses);
  };
  const std::vector<Outcome> first = stretch(0, 7, 4);
  for (const Outcome& o : first) ASSERT_TRUE(o.info && o.odom);
  for (int k = 4; k < 7; ++k) ASSERT_TRUE(first[k].info->lost) << k;
  const Eigen::Isometry3d held = toEigen(first[3].odom->pose.pose);
  const Eigen::Isometry3d reckoned = toEigen(first[6].odom->pose.pose);
  ASSERT_GT((reckoned.translation() - held.translation()).norm(), 0.03)
      << "three frames of motion on the wheels";

  // A parameter changed while lost: tracking restarts at frame 7 where the pose was published.
  reconfigure("target_points", 2000, true);
  const std::vector<Outcome> after_change = stretch(7, 8, 8);
  ASSERT_TRUE(after_change[0].info && after_change[0].odom);
  EXPECT_EQ(after_change[0].info->tracking, "first_frame");
  expectPoseNear(after_change[0].odom->pose.pose, reckoned, kExactPose,
                 "restart by dynamic_reconfigure while lost on the wheels");

  // Lost again (8-10 on the wheels, from frame 7), then the live clock steps 5 s back.
  const std::vector<Outcome> second = stretch(8, 11, 8);
  for (const Outcome& o : second) ASSERT_TRUE(o.info && o.info->lost && o.odom);
  const Eigen::Isometry3d reckoned_again = toEigen(second.back().odom->pose.pose);
  ASSERT_GT((reckoned_again.translation() - reckoned.translation()).norm(), 0.03);
  const ros::Time back = client->nextStamp() - ros::Duration(5.05);
  client->sendGuess(wheels[11], back);
  ros::WallDuration(0.02).sleep();
  client->send(client->frame(11), back);
  const Outcome stepped = client->outcome(back, true);
  reconfigure("target_points", 3000, true);
  ASSERT_TRUE(stepped.info && stepped.odom);
  EXPECT_EQ(stepped.info->tracking, "first_frame");
  expectPoseNear(stepped.odom->pose.pose, reckoned_again, kExactPose,
                 "restart by the live clock stepping back while lost on the wheels");
}

// Sets one parameter through the dynamic_reconfigure server; `list` is the request's list of
// that parameter's type (Config::bools, Config::strs, ...).
template <typename Param, typename Allocator, typename Value>
bool setParameter(std::vector<Param, Allocator> dynamic_reconfigure::Config::*list,
                  const std::string& name, const Value& value) {
  dynamic_reconfigure::Reconfigure srv;
  Param p;
  p.name = name;
  p.value = value;
  (srv.request.config.*list).push_back(p);
  return ros::service::call("acvo/set_parameters", srv);
}

bool setLostOdom(const std::string& value) {
  return setParameter(&dynamic_reconfigure::Config::strs, "lost_odom", value);
}

// lost_odom: none publishes no odometry message for a lost frame; null publishes rtabmap's null
// message (a zero pose, all-zero quaternion, 1e6 variances: publish_null_when_lost there). TF
// goes on at the held pose in both: a tree that stops breaks every consumer's lookups.
TEST(OdometryNodelet, LostFramesPublishNothingOrANullMessageWhenAskedTo) {
  if (client->late_base_tf_) GTEST_SKIP() << "covered by the other configurations";
  ASSERT_TRUE(client->reset());
  std::vector<ros::Time> stamps;
  const std::vector<Outcome> good = client->run(range(0, 3), &stamps);
  ASSERT_TRUE(good.back().odom);

  ASSERT_TRUE(setLostOdom("none"));
  const ros::Time t = client->nextStamp();
  client->send(client->blank(), t);
  client->flush();
  const Outcome o = client->outcome(t, false);
  ASSERT_TRUE(o.info);
  EXPECT_TRUE(o.info->lost);
  EXPECT_FALSE(o.odom) << "lost_odom none: no odometry message for a lost frame";
  const auto held_tf = client->lookup(t);
  ASSERT_TRUE(held_tf) << "lost_odom none: TF must go on";
  EXPECT_TRUE(tf2::transformToEigen(*held_tf).isApprox(toEigen(good.back().odom->pose.pose), 1e-6));

  ASSERT_TRUE(setLostOdom("null"));
  const ros::Time n = client->nextStamp();
  client->send(client->blank(), n);
  client->flush();
  const Outcome null = client->outcome(n, true);
  ASSERT_TRUE(null.info);
  EXPECT_TRUE(null.info->lost);
  ASSERT_TRUE(null.odom) << "lost_odom null: a null message is published for a lost frame";
  const auto& q = null.odom->pose.pose.orientation;
  EXPECT_EQ(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 0.0) << "a null pose";
  EXPECT_EQ(null.odom->pose.pose.position.x, 0.0);
  EXPECT_EQ(null.odom->child_frame_id, client->base_frame_);
  for (int d = 0; d < 6; ++d) {
    EXPECT_EQ(null.odom->pose.covariance[7 * d], acvo_ros::kLostVariance);
    EXPECT_EQ(null.odom->twist.covariance[7 * d], acvo_ros::kLostVariance);
  }
  const auto null_tf = client->lookup(n);
  ASSERT_TRUE(null_tf) << "lost_odom null: TF must go on";
  EXPECT_TRUE(tf2::transformToEigen(*null_tf).isApprox(toEigen(good.back().odom->pose.pose), 1e-6));
  ASSERT_TRUE(setLostOdom("held"));
}

bool callEmpty(const std::string& service) {
  std_srvs::Empty srv;
  return ros::service::call(service, srv);
}

// pause_odom: frames are dropped (no odom, no odom_info), diagnostics say "paused";
// resume_odom: the next frame is registered to the last tracked one and tracking goes on.
TEST(OdometryNodelet, PauseDropsFramesAndResumeGoesOn) {
  if (client->late_base_tf_) GTEST_SKIP() << "covered by the other configurations";
  ASSERT_TRUE(client->reset());
  const std::vector<Outcome> before = client->run(range(0, 4));
  ASSERT_TRUE(before.back().odom);
  ASSERT_TRUE(callEmpty("pause_odom"));
  std::vector<ros::Time> paused;
  for (int k = 4; k < 6; ++k) {
    paused.push_back(client->nextStamp());
    client->send(client->frame(k), paused.back());
  }
  // No flush(): its colour image (frame 0's) would wait in the approximate synchroniser and be
  // paired with the depth of the first frame after resume_odom. The last paused frame's set is
  // held there instead, and comes out (whole, after resume_odom) when the next frame arrives.
  for (const ros::Time& t : paused) {
    const Outcome o = client->outcome(t, false, 1.0);
    EXPECT_FALSE(o.info) << "a frame was processed while paused";
    EXPECT_FALSE(o.odom) << "a frame was published while paused";
  }
  const auto diag = client->waitDiagnostic(diagnostic_msgs::DiagnosticStatus::WARN, "paused");
  ASSERT_TRUE(diag);
  EXPECT_EQ(diag->message, "paused");
  ASSERT_TRUE(callEmpty("resume_odom"));
  const std::vector<Outcome> after = client->run(range(6, 9));
  for (const Outcome& o : after) {
    ASSERT_TRUE(o.info && o.odom);
    EXPECT_TRUE(isTracking(o.info->tracking)) << o.info->tracking << ": " << o.info->message;
  }
  // The first frame sent while paused never comes out (the last one may: the approximate
  // synchroniser holds it until the next frame, sent after resume_odom).
  EXPECT_EQ(client->infoCount(paused.front()), 0);
  expectPoseNear(after.back().odom->pose.pose, client->expectedBase(cameraPose(8)), Measured{0.0000486, 0.0000167},
                 "3 frames after a pause of 2 frames");
}

// A camera six times faster than the odometry (a slow machine, a slow frame): the subscriber
// queues (topic_queue_size 2) keep the newest frames and drop the older ones, so that the
// latency stays a few frames' processing instead of growing with a backlog, as it did when the
// subscriber queues were the synchroniser's 10. Stamps are the wall clock's here, so that
// odom_info.ms_latency is the time from the stamp to publishing.
TEST(OdometryNodelet, AFasterCameraIsDroppedNotQueued) {
  if (!client->burst_) GTEST_SKIP() << "needs nodelet_burst.test (a fresh nodelet, exact sync)";
  // One frame at a time: the time one frame takes, and its latency.
  std::vector<double> alone_total;
  for (int k = 0; k < 6; ++k) {
    const ros::Time t = ros::Time::now();
    client->send(client->frame(k), t);
    const Outcome o = client->outcome(t, true);
    ASSERT_TRUE(o.info && o.odom) << "frame " << k;
    if (k > 0) alone_total.push_back(o.info->ms_total);  // the first warms the engine up
    // The latency holds the processing and the transport of the images.
    EXPECT_GE(o.info->ms_latency, o.info->ms_total);
    std::cout << "[ MEASURED ] alone, frame " << k << ": ms_total " << o.info->ms_total
              << ", ms_latency " << o.info->ms_latency << "\n";
  }
  std::sort(alone_total.begin(), alone_total.end());
  const double typical = alone_total[alone_total.size() / 2];
  const double slowest = alone_total.back();
  // The stream: kFrames frames at a sixth of the time one typically takes alone (a load spike
  // during the frames alone must not make the camera slower than the odometry). A frame of the
  // stream costs less than one alone (no keyframe at every frame): at a quarter, 11-14 of 30
  // were processed once the selection and the kernel pass got cheaper (four runs, 2026-11-26),
  // and the camera was no longer four times faster than the odometry.
  constexpr int kFrames = 30;
  const double period = typical / 6000.0;  // s
  std::vector<ros::Time> stamps;
  std::vector<Client::Messages> stream;
  for (int i = 0; i < kFrames; ++i) client->frame(6 + i);  // rendered ahead
  const ros::Time start = ros::Time::now() + ros::Duration(0.5);
  for (int i = 0; i < kFrames; ++i) {
    stamps.push_back(start + ros::Duration(period * i));
    stream.push_back(client->messages(client->frame(6 + i), stamps.back()));
  }
  for (int i = 0; i < kFrames; ++i) {
    const ros::Duration wait = stamps[i] - ros::Time::now();
    if (wait > ros::Duration(0)) wait.sleep();
    client->publish(stream[i]);
  }
  // The last frame comes out: everything before it is done then.
  const Outcome last = client->outcome(stamps.back(), true);
  ASSERT_TRUE(last.info && last.odom) << "the newest frame must be processed";
  std::vector<double> latency;
  for (const ros::Time& t : stamps) {
    const Outcome o = client->outcome(t, false, 0.01);
    if (o.info) latency.push_back(o.info->ms_latency);
  }
  const double worst = *std::max_element(latency.begin(), latency.end());
  std::cout << "[ MEASURED ] " << kFrames << " frames every " << period * 1000.0
            << " ms (one takes " << typical << " ms alone, up to " << slowest
            << " ms): " << latency.size() << " processed; latency first " << latency.front()
            << " ms, last " << latency.back() << " ms, worst " << worst << " ms\n";
  // A backlog processes every frame it holds, each later than the one before: with 10 queued
  // per topic (as before) 16-21 of 30 were processed and the latency grew to 455-475 ms. The
  // figures of today's queues: scripts/measure_ros_bounds.
  constexpr int kMostProcessed = kFrames * 2 / 5;
  expectTiming("burst, frames processed of 30", double(latency.size()), "<=", kMostProcessed,
               "frames", "a backlog, every frame processed in turn (16-21 of 30 with 10 queued "
               "per topic)");
  expectTiming("burst, worst latency", worst, "<", kQueuedFrames * slowest + kLatencySlack, "ms",
               "a backlog: more than the frames the queues hold ahead of a new one, each a "
               "slowest frame's processing, plus 100 ms of transport (475 ms with 10 queued "
               "per topic)");
  EXPECT_TRUE(isTracking(last.info->tracking)) << last.info->message;
}

TEST(OdometryNodelet, MissingBaseTransformIsReportedNotReplacedByIdentity) {
  if (!client->late_base_tf_) GTEST_SKIP() << "needs a .test without the base transform";
  ASSERT_TRUE(client->reset());
  // No transform from the base to the camera yet: the odometry runs, nothing is published,
  // odom_info says why. The nodelet waits for the transform once (wait_for_transform_duration
  // 1 s in the .test), not at every frame: each wait blocked the callback queue.
  std::vector<Outcome> without = client->run(range(0, 4));
  double slowest_after_first = 0.0;  // ms
  for (std::size_t k = 0; k < without.size(); ++k) {
    const Outcome& o = without[k];
    ASSERT_TRUE(o.info);
    EXPECT_FALSE(o.odom) << "published without the base transform";
    EXPECT_NE(o.info->message.find("not published: no transform"), std::string::npos)
        << o.info->message;
    std::cout << "[ MEASURED ] without the base transform, frame " << k << ": ms_total "
              << o.info->ms_total << "\n";
    if (k > 0) slowest_after_first = std::max(slowest_after_first, o.info->ms_total);
  }
  // The first frame waits (1 s); the next ones must not.
  expectTiming("without the base transform, slowest frame after the first", slowest_after_first,
               "<", 500.0, "ms",
               "a wait for the base transform at every frame (wait_for_transform_duration 1 s "
               "in the .test)");
  // The transform appears: the next frames are published, conjugated by it, and continue the
  // motion measured meanwhile.
  tf2_ros::StaticTransformBroadcaster broadcaster;
  geometry_msgs::TransformStamped t = tf2::eigenToTransform(client->base_from_camera_);
  t.header.stamp = ros::Time::now();
  t.header.frame_id = client->base_frame_;
  t.child_frame_id = acvo_ros::stripSlash(client->camera_frame_);
  broadcaster.sendTransform(t);
  ros::WallDuration(0.5).sleep();
  std::vector<Outcome> with = client->run(range(4, 7));
  ASSERT_TRUE(with.back().odom);
  EXPECT_EQ(with.back().odom->child_frame_id, client->base_frame_);
  expectPoseNear(with.back().odom->pose.pose, client->expectedBase(cameraPose(6)), Measured{0.00000464, 0.00000705},
                 "after the base transform arrived");
}

// camera_info of a 640x480 camera with 2x2 binning for 320x240 images, whose K (the raw image's)
// differs from P: the intrinsics are P's, halved. The depth images carry another frame_id than
// the colour's: warned about once.
TEST(OdometryNodelet, ABinnedStreamIsMeasuredWithItsProjectionMatrix) {
  if (!client->binned_) GTEST_SKIP() << "needs nodelet_inputs.test";
  const ros::WallTime since = ros::WallTime::now();
  ASSERT_TRUE(client->reset());
  const std::vector<Outcome> out = client->run(range(0, 7));
  for (const Outcome& o : out) {
    ASSERT_TRUE(o.info);
    ASSERT_TRUE(o.odom) << o.info->tracking << ": " << o.info->message;
  }
  EXPECT_TRUE(isTracking(out.back().info->tracking)) << out.back().info->message;
  expectPoseNear(out.back().odom->pose.pose, client->expectedBase(cameraPose(6)), Measured{0.0000107, 0.0000104},
                 "binned stream, intrinsics from P");
  if (client->depth_frame_ != acvo_ros::stripSlash(client->camera_frame_)) {
    const auto warning = client->waitLog("frame_id '" + client->depth_frame_ + "' differs", since);
    ASSERT_TRUE(warning) << "no warning about the depth image's frame_id";
    EXPECT_NE(warning->find("TUM"), std::string::npos) << *warning;
  }
}

// The .test sets a valid selection/target_points (1200: 600 at 320x240), an invalid
// coarse_to_fine/ell_min (-1), an unknown frame_id and max_depth, dynparam's name of
// selection/max_depth, which nothing reads. The bad value alone is rejected (before, one bad
// value put every parameter back to its default: 1500 points from test_params.yaml's would have
// been lost too); the unknown name is reported with the name it has here, max_depth with its
// section. All stay in diagnostics.
TEST(OdometryNodelet, ABadParameterIsRejectedAloneAndAnUnknownOneIsNamed) {
  if (!client->bad_params_) GTEST_SKIP() << "needs nodelet_inputs.test";
  ASSERT_TRUE(client->reset());
  const std::vector<Outcome> out = client->run(range(0, 3));
  ASSERT_TRUE(out.back().info);
  EXPECT_LE(out.back().info->moving_points, 600u) << "the valid target_points was dropped";
  EXPECT_GT(out.back().info->moving_points, 300u);
  const auto problems = client->diagnosticValue("parameter problems");
  ASSERT_TRUE(problems);
  std::cout << "[ MEASURED ] parameter problems: " << *problems << "\n";
  EXPECT_NE(problems->find("~coarse_to_fine/ell_min rejected"), std::string::npos) << *problems;
  EXPECT_NE(problems->find("~frame_id"), std::string::npos) << *problems;
  EXPECT_NE(problems->find("base_frame_id"), std::string::npos) << *problems;
  EXPECT_NE(problems->find("~max_depth = 4.5 is not read (ignored): the parameter is "
                           "~selection/max_depth"),
            std::string::npos)
      << *problems;
  EXPECT_EQ(problems->find("target_points"), std::string::npos) << *problems;
}

// Whether the depth is registered to the colour is judged from the images (every frame until
// 10 with enough depth edges): the registered room of the tests before says so in diagnostics
// without a warning. A camera whose colour comes from a second camera with 0.897 times the focal
// length (7-Scenes', a raw depth image's) is judged again from its first frame and named with
// what to do; its frames are still processed, their colour resampled to the depth camera from
// then on (odometry/unregistered_colour).
TEST(OdometryNodelet, DepthNotRegisteredToTheColourIsNamed) {
  const ros::WallTime since = ros::WallTime::now();
  ASSERT_TRUE(client->reset());
  client->run(range(0, 31));
  auto judged = [](const std::string& want) {
    return client->diagnosticValueOnce("colour/depth registration",
                                       [&](const std::string& v) { return v == want; });
  };
  EXPECT_EQ(judged("registered"), "registered");
  EXPECT_FALSE(client->waitLog("does not look registered", since, 0.5));

  const std::string other_camera = "unregistered_camera_optical_frame";
  for (int k = 31; k < 70; ++k) {
    const RgbdImage img = acvo_test::renderRoom(
        acvo_test::worldFromFirstCamera() * cameraPose(k), acvo_test::testCamera(), 0.897);
    const ros::Time t = client->nextStamp();
    client->send(img, t, [&](auto& rgb, auto& depth, auto& info) {
      rgb.header.frame_id = depth.header.frame_id = info.header.frame_id = other_camera;
    });
    client->flush();
    const Outcome o = client->outcome(t, false);
    ASSERT_TRUE(o.info) << "frame " << k << ": no odom_info";
    EXPECT_NE(o.info->tracking, "bad_frame") << o.info->message;
  }
  const auto warning = client->waitLog("does not look registered", since);
  ASSERT_TRUE(warning) << "no warning about the unregistered depth";
  EXPECT_NE(warning->find("depth_registered"), std::string::npos) << *warning;
  const auto at = warning->find("focal length ");
  ASSERT_NE(at, std::string::npos) << *warning;
  EXPECT_NEAR(std::stod(warning->substr(at + 13, 4)), 0.897, 0.03) << *warning;
  EXPECT_NE(warning->find("resampled"), std::string::npos) << *warning;
  const std::string resampled = "unregistered (colour resampled to the depth camera)";
  EXPECT_EQ(judged(resampled), resampled);
}

bool setSyncDepth(const std::string& how) {
  return setParameter(&dynamic_reconfigure::Config::strs, "sync_depth", how);
}

// Colour and depth of different stamps (the approximate configurations send the depth 7 ms
// after the colour; test_params.yaml pairs them as they come): the diagnostics say by how much
// and, with odometry/sync_depth own_motion, that the depth was moved to the colour's time.
TEST(OdometryNodelet, DepthOfAnotherStampIsShownMovedInTheDiagnostics) {
  auto shown = [](const std::string& want) {
    auto contains = [&](const std::string& v) { return v.find(want) != std::string::npos; };
    return client->diagnosticValueOnce("colour stamp - depth stamp (ms)", contains)
        .value_or("(none)");
  };
  ASSERT_TRUE(client->reset());
  client->run(range(0, 5));
  if (!client->approx_) {
    EXPECT_EQ(shown("0.00"), "0.00");
    return;
  }
  EXPECT_EQ(shown("-7.00"), "-7.00");
  ASSERT_TRUE(setSyncDepth("own_motion"));
  client->run(range(5, 25));
  const std::string v = shown("moved");
  ASSERT_TRUE(setSyncDepth("none"));
  EXPECT_EQ(v, "-7.00, depth moved to the colour's time");
}

TEST(OdometryNodelet, NoDataIsAnError) {
  // no_data_timeout is 3 s in test_params.yaml.
  const auto diag =
      client->waitDiagnostic(diagnostic_msgs::DiagnosticStatus::ERROR, "no data", 8.0);
  ASSERT_TRUE(diag);
  EXPECT_EQ(diag->message, "no data");
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_odometry_nodelet");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  Client c;
  client = &c;
  if (!c.connect()) {
    std::cerr << "the nodelet did not come up (topics or reset_odom missing)\n";
    return 1;
  }
  const int result = RUN_ALL_TESTS();
  client = nullptr;
  // No callback may reach the client while it is destroyed (a late odom or TF message would
  // lock a destroyed mutex).
  spinner.stop();
  ros::shutdown();
  return result;
}
