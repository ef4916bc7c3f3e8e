// What makes a frame unusable (Frame::problem): sizes, types, intrinsics, stamp; its grey image.
#include "acvo/cloud/frame.hpp"

#include <cmath>
#include <sstream>

#include <opencv2/imgproc.hpp>

namespace acvo {

std::string Frame::problem() const {
  std::ostringstream why;
  if (color.empty()) return "colour image is empty";
  if (depth.empty()) return "depth image is empty";
  const int want_color = order == ColorOrder::kGray ? CV_8UC1 : CV_8UC3;
  if (color.type() != want_color) {
    why << "colour image has type " << cv::typeToString(color.type()) << ", expected "
        << cv::typeToString(want_color);
    return why.str();
  }
  if (depth.type() != CV_32FC1) {
    return "depth image has type " + cv::typeToString(depth.type()) + ", expected 32FC1 metres";
  }
  if (color.size() != depth.size()) {
    why << "colour is " << color.cols << "x" << color.rows << " but depth is " << depth.cols << "x"
        << depth.rows;
    return why.str();
  }
  if (!camera.valid()) return "camera intrinsics are invalid (zero or non-finite focal length)";
  // A NaN stamp would enter every later interval and covariance growth until a reset.
  if (!std::isfinite(stamp)) return "stamp is not finite";
  // A non-finite depth stamp would move the depth by a non-finite delay: no point left.
  if (!std::isfinite(depth_stamp)) {
    why << "depth_stamp is not finite (" << depth_stamp << ")";
    return why.str();
  }
  if (camera.width != color.cols || camera.height != color.rows) {
    why << "camera is " << camera.width << "x" << camera.height << " but the images are "
        << color.cols << "x" << color.rows;
    return why.str();
  }
  return {};
}

cv::Mat grayImage(const Frame& frame) {
  if (frame.order == ColorOrder::kGray) return frame.color;
  cv::Mat gray;
  cv::cvtColor(frame.color, gray,
               frame.order == ColorOrder::kRgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

}  // namespace acvo
