#include "conversions.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include <image_geometry/pinhole_camera_model.h>
#include <pcl_conversions/pcl_conversions.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <opencv2/imgproc.hpp>

#include "acvo/cloud/depth.hpp"
#include "point_types.hpp"

namespace acvo_ros {
namespace enc = sensor_msgs::image_encodings;

namespace {

bool hostIsBigEndian() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

// A view of the message's pixels (no copy); valid while `msg` lives.
cv::Mat view(const sensor_msgs::Image& msg, int cv_type) {
  return cv::Mat(static_cast<int>(msg.height), static_cast<int>(msg.width), cv_type,
                 const_cast<std::uint8_t*>(msg.data.data()), msg.step);
}

// Whether camera_info's projection matrix P is filled; a driver that fills K alone leaves it all
// zero, and K is read instead.
bool hasProjection(const sensor_msgs::CameraInfo& info) {
  return info.P[0] != 0.0 || info.P[5] != 0.0;
}

}  // namespace

std::string stripSlash(const std::string& frame_id) {
  std::size_t first = 0;
  while (first < frame_id.size() && frame_id[first] == '/') ++first;
  return frame_id.substr(first);
}

std::string layoutProblem(const sensor_msgs::Image& msg) {
  int channels = 0, bits = 0;
  try {
    channels = enc::numChannels(msg.encoding);
    bits = enc::bitDepth(msg.encoding);
  } catch (const std::exception&) {
    return "unknown encoding '" + msg.encoding + "'";
  }
  if (msg.width == 0 || msg.height == 0) return "empty image (0 pixels)";
  if (bits > 8 && static_cast<bool>(msg.is_bigendian) != hostIsBigEndian()) {
    return "byte order of the data differs from this machine's (is_bigendian = " +
           std::to_string(msg.is_bigendian) + ")";
  }
  // An image row starts on a whole element: cv::Mat (and every consumer of the data) assumes it.
  const std::uint32_t element = static_cast<std::uint32_t>(std::max(bits / 8, 1));
  if (msg.step % element != 0) {
    return "step " + std::to_string(msg.step) + " is not a multiple of the " +
           std::to_string(element) + "-byte element of " + msg.encoding;
  }
  const std::uint64_t row_bytes = std::uint64_t{msg.width} * channels * bits / 8;
  if (msg.step < row_bytes) {
    return "step " + std::to_string(msg.step) + " is shorter than a row of " +
           std::to_string(msg.width) + " " + msg.encoding + " pixels (" +
           std::to_string(row_bytes) + " bytes)";
  }
  const std::uint64_t needed = std::uint64_t{msg.step} * msg.height;
  if (msg.data.size() < needed) {
    return "truncated data: " + std::to_string(msg.data.size()) + " bytes for " +
           std::to_string(msg.height) + " rows of step " + std::to_string(msg.step) + " (" +
           std::to_string(needed) + " bytes)";
  }
  return {};
}

ColorImage decodeColor(const sensor_msgs::Image& msg) {
  ColorImage out;
  const std::string& e = msg.encoding;
  if (e != enc::RGB8 && e != enc::BGR8 && e != enc::RGBA8 && e != enc::BGRA8 && e != enc::MONO8) {
    out.problem =
        "unsupported colour encoding '" + e + "' (expected rgb8, bgr8, rgba8, bgra8 or mono8)";
    return out;
  }
  out.problem = layoutProblem(msg);
  if (!out.problem.empty()) return out;

  if (e == enc::RGB8 || e == enc::BGR8) {
    out.image = view(msg, CV_8UC3).clone();
  } else if (e == enc::RGBA8 || e == enc::BGRA8) {
    // Same conversion code for both: dropping the 4th channel keeps the channel order.
    cv::cvtColor(view(msg, CV_8UC4), out.image, cv::COLOR_RGBA2RGB);
  } else {
    out.image = view(msg, CV_8UC1).clone();
  }
  out.order = (e == enc::MONO8)                     ? acvo::ColorOrder::kGray
              : (e == enc::RGB8 || e == enc::RGBA8) ? acvo::ColorOrder::kRgb
                                                    : acvo::ColorOrder::kBgr;
  return out;
}

DepthImage decodeDepth(const sensor_msgs::Image& msg) {
  DepthImage out;
  int cv_type = 0;
  if (msg.encoding == enc::TYPE_16UC1 || msg.encoding == enc::MONO16) {
    cv_type = CV_16UC1;
    out.units_per_metre = 1000.0;  // REP 118: 16-bit depth is in millimetres
  } else if (msg.encoding == enc::TYPE_32FC1) {
    cv_type = CV_32FC1;
    out.units_per_metre = 1.0;
  } else {
    out.problem = "unsupported depth encoding '" + msg.encoding +
                  "' (expected 16UC1 millimetres or 32FC1 metres)";
    return out;
  }
  out.problem = layoutProblem(msg);
  if (!out.problem.empty()) return out;
  out.metres = acvo::depthToMeters(view(msg, cv_type), out.units_per_metre);
  return out;
}

std::string IntrinsicsOverride::problem() const {
  const bool any = fx != 0.0 || fy != 0.0 || cx != 0.0 || cy != 0.0;
  if (any && !explicitValues()) {
    return "fx, fy, cx, cy must all be set to override the intrinsics (fx, fy not zero, cx, cy "
           "positive; got " +
           std::to_string(fx) + ", " + std::to_string(fy) + ", " + std::to_string(cx) + ", " +
           std::to_string(cy) + ")";
  }
  if (named()) {
    try {
      acvo::cameraByName(camera);
    } catch (const std::exception& e) {
      return "camera '" + camera + "': " + e.what() + " (use \"\" or \"info\" for camera_info)";
    }
  }
  return {};
}

namespace {

// Named intrinsics are for 640x480; a driver streaming another resolution of the same sensor
// scales them (the principal point about the image corner, pixel centres being at integer
// coordinates).
acvo::Camera namedCameraFor(const std::string& name, int width, int height) {
  acvo::Camera cam = acvo::cameraByName(name);
  const double sx = static_cast<double>(width) / cam.width;
  const double sy = static_cast<double>(height) / cam.height;
  cam.fx *= sx;
  cam.fy *= sy;
  cam.cx = (cam.cx + 0.5) * sx - 0.5;
  cam.cy = (cam.cy + 0.5) * sy - 0.5;
  return cam;
}

// The intrinsics camera_info gives for images of width x height into `cam`: empty, or why not.
std::string intrinsicsFromInfo(const sensor_msgs::CameraInfo& info, int width, int height,
                               acvo::Camera& cam) {
  // image_geometry reads camera_info as the ROS drivers mean it: the projection matrix P (the
  // rectified image's intrinsics, which K is not for a distorted camera), scaled for binning and
  // shifted for a region of interest.
  image_geometry::PinholeCameraModel model;
  try {
    model.fromCameraInfo(info);
  } catch (const std::exception& e) {
    return std::string("camera_info cannot be read: ") + e.what();
  }
  const cv::Size reduced = model.reducedResolution();
  if (reduced.width != width || reduced.height != height) {
    const bool scaled = info.binning_x > 1 || info.binning_y > 1 || info.roi.width > 0;
    return "camera_info size " + std::to_string(info.width) + "x" + std::to_string(info.height) +
           (scaled ? " (" + std::to_string(reduced.width) + "x" +
                         std::to_string(reduced.height) + " after binning and ROI)"
                   : std::string()) +
           " differs from the image's " + std::to_string(width) + "x" + std::to_string(height);
  }
  // A driver that fills K alone (P all zero): K, adjusted alike.
  const bool has_p = hasProjection(info);
  const cv::Matx33d k =
      has_p ? model.projectionMatrix().get_minor<3, 3>(0, 0) : model.intrinsicMatrix();
  cam.fx = k(0, 0);
  cam.fy = k(1, 1);
  cam.cx = k(0, 2);
  cam.cy = k(1, 2);
  // (A negative focal length is a mirrored image axis, as acvo::Camera takes it.)
  if (!(cam.fx != 0.0 && cam.fy != 0.0 && std::isfinite(cam.fx) && std::isfinite(cam.fy) &&
        std::isfinite(cam.cx) && std::isfinite(cam.cy))) {
    return std::string("camera_info ") + (has_p ? "P" : "K") +
           " has a zero or non-finite focal length or centre (fx " + std::to_string(cam.fx) +
           ", fy " + std::to_string(cam.fy) + ")";
  }
  return {};
}

}  // namespace

CameraResult cameraFor(const sensor_msgs::CameraInfo& info, int width, int height,
                       const IntrinsicsOverride& override_intrinsics) {
  CameraResult out;
  out.problem = override_intrinsics.problem();
  if (!out.problem.empty()) return out;
  acvo::Camera& cam = out.camera;
  if (override_intrinsics.explicitValues()) {
    cam.fx = override_intrinsics.fx;
    cam.fy = override_intrinsics.fy;
    cam.cx = override_intrinsics.cx;
    cam.cy = override_intrinsics.cy;
  } else if (override_intrinsics.named()) {
    cam = namedCameraFor(override_intrinsics.camera, width, height);
  } else {
    out.problem = intrinsicsFromInfo(info, width, height, cam);
    if (!out.problem.empty()) return out;
  }
  cam.width = width;
  cam.height = height;
  cam.depth_scale = 1.0;  // the frame's depth is already in metres
  return out;
}

std::string describeCamera(const acvo::Camera& camera, const IntrinsicsOverride& source,
                           const InputTopics& topics) {
  std::ostringstream text;
  text << "fx " << camera.fx << ", fy " << camera.fy << ", cx " << camera.cx << ", cy "
       << camera.cy << " (" << camera.width << "x" << camera.height << ") ";
  if (camera.mirrored()) {
    text << "(a negative focal length: that image axis runs against the optical frame's, "
            "mirrored) ";
  }
  if (source.explicitValues()) {
    text << "from the parameters fx, fy, cx, cy";
  } else if (source.named()) {
    text << "from the parameter camera: " << source.camera;
  } else {
    text << "from camera_info on " << topics.info;
  }
  return text.str();
}

bool distortedCameraInfo(const sensor_msgs::CameraInfo& info, const IntrinsicsOverride& source) {
  return source.fromCameraInfo() &&
         std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0.0; });
}

bool rectifiedTopic(const std::string& topic) {
  const std::size_t slash = topic.rfind('/');
  const std::string name = slash == std::string::npos ? topic : topic.substr(slash + 1);
  // "rect" at the start of a word (image_rect, rect_color), not inside one ("direct").
  for (std::size_t at = name.find("rect"); at != std::string::npos; at = name.find("rect", at + 1)) {
    if (at == 0 || !std::isalpha(static_cast<unsigned char>(name[at - 1]))) return true;
  }
  return false;
}

std::string unrectifiedWarning(const sensor_msgs::CameraInfo& info,
                               const IntrinsicsOverride& source, const InputTopics& topics) {
  if (!distortedCameraInfo(info, source) || rectifiedTopic(topics.rgb)) return {};
  return "camera_info on " + topics.info + " has a non-zero distortion (D) and the colour topic " +
         topics.rgb +
         " is not a rectified one (its name holds no \"rect\"): the images are used as if "
         "rectified, so a distorted camera's points are off towards the image's edges. Subscribe "
         "to the rectified images (image_proc's image_rect_color, a driver's rectified topic); "
         "images rectified under another name are right as they are";
}

bool nominalCameraInfo(const sensor_msgs::CameraInfo& info, const IntrinsicsOverride& source) {
  if (!source.fromCameraInfo() || distortedCameraInfo(info, source)) return false;
  // The full sensor's intrinsics, before binning and a region of interest (P, or K where P is all
  // zero, as cameraFor reads them): a driver's defaults are about that image's centre.
  const bool has_p = hasProjection(info);
  acvo::Camera full;
  full.fx = has_p ? info.P[0] : info.K[0];
  full.fy = has_p ? info.P[5] : info.K[4];
  full.cx = has_p ? info.P[2] : info.K[2];
  full.cy = has_p ? info.P[6] : info.K[5];
  full.width = int(info.width);
  full.height = int(info.height);
  return acvo::nominalIntrinsics(full, acvo::LensDistortion{});
}

std::variant<acvo::Frame, Rejection> frameFromMessages(const sensor_msgs::Image& rgb,
                                                       const sensor_msgs::Image& depth,
                                                       const sensor_msgs::CameraInfo& info,
                                                       const IntrinsicsOverride& intrinsics,
                                                       const InputTopics& topics) {
  if (stripSlash(rgb.header.frame_id).empty()) {
    return Rejection{"the colour image on " + topics.rgb + " has no frame_id"};
  }
  ColorImage color = decodeColor(rgb);
  if (!color.problem.empty()) return Rejection{color.problem + " on " + topics.rgb};
  DepthImage metres = decodeDepth(depth);
  if (!metres.problem.empty()) return Rejection{metres.problem + " on " + topics.depth};
  if (rgb.width != depth.width || rgb.height != depth.height) {
    return Rejection{"colour (" + topics.rgb + ", " + std::to_string(rgb.width) + "x" +
                     std::to_string(rgb.height) + ") and depth (" + topics.depth + ", " +
                     std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                     ") differ in size: the depth must be registered to the colour image"};
  }
  CameraResult camera = cameraFor(info, rgb.width, rgb.height, intrinsics);
  if (!camera.problem.empty()) return Rejection{camera.problem + " (" + topics.info + ")"};
  acvo::Frame frame;
  frame.color = color.image;
  frame.order = color.order;
  frame.depth = metres.metres;
  frame.camera = camera.camera;
  frame.stamp = rgb.header.stamp.toSec();
  frame.depth_stamp = depth.header.stamp.toSec();
  if (std::string problem = frame.problem(); !problem.empty()) return Rejection{problem};
  return frame;
}

Eigen::Isometry3d conjugate(const Eigen::Isometry3d& base_from_cam, const Eigen::Isometry3d& t) {
  return base_from_cam * t * base_from_cam.inverse();
}

Twist twistOf(const Eigen::Isometry3d& delta, double dt) {
  Twist out;
  if (!(dt > 0.0)) return out;
  const Eigen::AngleAxisd aa(delta.rotation());
  out.linear = delta.translation() / dt;
  out.angular = aa.axis() * aa.angle() / dt;
  return out;
}

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& pose) {
  return tf2::toMsg(pose);
}

Eigen::Isometry3d fromPoseMsg(const geometry_msgs::Pose& pose, std::string* problem) {
  const auto& q = pose.orientation;
  Eigen::Quaterniond quat(q.w, q.x, q.y, q.z);
  const auto& p = pose.position;
  if (!(quat.norm() > 1e-9) || !std::isfinite(quat.norm()) || !std::isfinite(p.x) ||
      !std::isfinite(p.y) || !std::isfinite(p.z)) {
    if (problem) *problem = "the pose has a zero or non-finite orientation or position";
    return Eigen::Isometry3d::Identity();
  }
  quat.normalize();
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = quat.toRotationMatrix();
  out.translation() = Eigen::Vector3d(p.x, p.y, p.z);
  if (problem) problem->clear();
  return out;
}

geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& pose,
                                               const std::string& parent, const std::string& child,
                                               const ros::Time& stamp) {
  geometry_msgs::TransformStamped t = tf2::eigenToTransform(pose);
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  return t;
}

sensor_msgs::PointCloud2 toPointCloud2(const acvo::LabelledCloud& cloud,
                                       const std_msgs::Header& header) {
  pcl::PointCloud<LabelledPoint> pc;
  pc.resize(cloud.size());  // width = size, height = 1
  const bool has_rgb = cloud.rgb.size() == cloud.size();
  const bool has_labels = cloud.labels.size() == cloud.size();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    LabelledPoint& p = pc[i];
    p.x = cloud.points[i].x();
    p.y = cloud.points[i].y();
    p.z = cloud.points[i].z();
    if (has_rgb) {
      p.r = cloud.rgb[i][0];
      p.g = cloud.rgb[i][1];
      p.b = cloud.rgb[i][2];
    } else {
      p.r = p.g = p.b = 128;
    }
    p.a = 255;
    const acvo::Label l = has_labels ? cloud.labels[i] : acvo::Label::Zero();
    p.hue = l[0];
    p.saturation = l[1];
    p.value = l[2];
    p.gradient_x = l[3];
    p.gradient_y = l[4];
  }
  pc.is_dense = true;
  sensor_msgs::PointCloud2 msg;
  pcl::toROSMsg(pc, msg);
  msg.header = header;  // the ROS stamp as it came, not through PCL's microseconds
  return msg;
}

}  // namespace acvo_ros
