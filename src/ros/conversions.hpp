// Messages <-> core types for the odometry nodelet: images and camera info to an acvo::Frame,
// poses to messages, the labelled cloud to PointCloud2. No state, no algorithm; every decoder
// returns a value with an empty `problem` on success or a sentence saying what is wrong.
#pragma once

#include <cmath>
#include <string>
#include <variant>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"
#include "acvo/cloud/frame.hpp"
#include "acvo/cloud/labelled_cloud.hpp"

namespace acvo_ros {

// TUM bags and older drivers write frame ids as "/name"; tf2 wants "name".
std::string stripSlash(const std::string& frame_id);

// Why the image's buffer cannot be read as `encoding` (unknown encoding, big-endian data, step
// shorter than a row, data shorter than step * height); empty when it can.
std::string layoutProblem(const sensor_msgs::Image& msg);

struct ColorImage {
  cv::Mat image;  // CV_8UC3 in `order`, or CV_8UC1 for mono8; owns its pixels
  acvo::ColorOrder order = acvo::ColorOrder::kRgb;
  std::string problem;
};
// rgb8, bgr8, rgba8, bgra8 (alpha dropped) and mono8.
ColorImage decodeColor(const sensor_msgs::Image& msg);

struct DepthImage {
  cv::Mat metres;                // CV_32FC1, 0 = invalid
  double units_per_metre = 1.0;  // 1000 for 16UC1 millimetres, 1 for 32FC1 metres
  std::string problem;
};
// 16UC1 (millimetres, 0 = invalid) and 32FC1 (metres, NaN/0 = invalid).
DepthImage decodeDepth(const sensor_msgs::Image& msg);

// Where intrinsics come from when not from CameraInfo: a TUM name ("fr1", "fr2", "fr3",
// "default"; "" or "info" = use CameraInfo) or explicit fx, fy, cx, cy (fx, fy non-zero: a negative
// one is a mirrored axis; cx, cy > 0).
struct IntrinsicsOverride {
  std::string camera;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;

  bool explicitValues() const {
    return std::isfinite(fx) && fx != 0.0 && std::isfinite(fy) && fy != 0.0 && cx > 0.0 &&
           cy > 0.0 && std::isfinite(cx) && std::isfinite(cy);
  }
  bool named() const { return !camera.empty() && camera != "info"; }
  bool fromCameraInfo() const { return !explicitValues() && !named(); }
  // Empty when consistent; otherwise says what is wrong (unknown name, partial fx..cy).
  std::string problem() const;
};

struct CameraResult {
  acvo::Camera camera;
  std::string problem;
};
// Intrinsics of a width x height colour image: explicit override, else the named camera
// (scaled when the image is not 640x480), else CameraInfo's projection matrix P through
// image_geometry::PinholeCameraModel (binning and ROI applied; K when P is all zero), whose
// size after binning and ROI must match the image and whose focal lengths must be finite and not
// zero (a negative one is a mirrored axis, as acvo::Camera takes it).
CameraResult cameraFor(const sensor_msgs::CameraInfo& info, int width, int height,
                       const IntrinsicsOverride& override_intrinsics);

// The names of the three input topics, for messages about them.
struct InputTopics {
  std::string rgb, depth, info;
};

// The intrinsics in use and where they come from, for /rosout and the diagnostics, e.g.
// "fx 585, fy 585, cx 320, cy 240 (640x480) from camera_info on /camera/rgb/camera_info".
std::string describeCamera(const acvo::Camera& camera, const IntrinsicsOverride& source,
                           const InputTopics& topics);
// Whether the intrinsics in use are camera_info's and its D has a non-zero coefficient (the
// images are then used as if rectified).
bool distortedCameraInfo(const sensor_msgs::CameraInfo& info, const IntrinsicsOverride& source);
// Whether a topic is, by its name, a rectified image: its last name holds a word starting with
// "rect" (image_proc's image_rect and image_rect_color, a driver's image_rect_raw).
bool rectifiedTopic(const std::string& topic);
// The warning for images that may be distorted: camera_info's D in use is not zero and the
// colour topic is not a rectified one (rectifiedTopic); "" otherwise. Drivers publish the
// calibration's D with their rectified images too, so D alone says nothing.
std::string unrectifiedWarning(const sensor_msgs::CameraInfo& info,
                               const IntrinsicsOverride& source, const InputTopics& topics);
// Whether the intrinsics in use are camera_info's and nominal rather than a calibration
// (acvo::nominalIntrinsics, with camera_info's D all zero): a driver's or a dataset's defaults.
// Judged at camera_info's full resolution (its P or K and width x height), so a binned stream
// or a region of interest of a nominal camera is told nominal too.
bool nominalCameraInfo(const sensor_msgs::CameraInfo& info, const IntrinsicsOverride& source);

// Why a set of messages was not made into a frame: a sentence naming the cause and the topic.
struct Rejection {
  std::string why;
};

// The frame of one synchronised set (colour, registered depth, camera info), or why there is
// none: no frame id, an unsupported or malformed encoding, colour and depth of different sizes,
// unusable intrinsics. The stamp is the colour image's.
std::variant<acvo::Frame, Rejection> frameFromMessages(const sensor_msgs::Image& rgb,
                                                       const sensor_msgs::Image& depth,
                                                       const sensor_msgs::CameraInfo& info,
                                                       const IntrinsicsOverride& intrinsics,
                                                       const InputTopics& topics);

// Optical-frame camera motion seen from a base frame rigidly attached to the camera:
// T_base_cam * T * T_base_cam^-1.
Eigen::Isometry3d conjugate(const Eigen::Isometry3d& base_from_cam, const Eigen::Isometry3d& t);

// Twist (linear, angular) of a relative motion `delta` that took `dt` seconds, expressed in the
// frame the motion starts from.
struct Twist {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
};
Twist twistOf(const Eigen::Isometry3d& delta, double dt);

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& pose);
// The orientation is normalised; an all-zero quaternion is an error reported in `problem`.
Eigen::Isometry3d fromPoseMsg(const geometry_msgs::Pose& pose, std::string* problem);

geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& pose,
                                               const std::string& parent, const std::string& child,
                                               const ros::Time& stamp);

// The cloud as pcl::PointCloud<LabelledPoint> (point_types.hpp: xyz, packed rgb and the five
// labels), unorganised, in the camera frame of `header`, converted by pcl::toROSMsg.
sensor_msgs::PointCloud2 toPointCloud2(const acvo::LabelledCloud& cloud,
                                       const std_msgs::Header& header);

}  // namespace acvo_ros
