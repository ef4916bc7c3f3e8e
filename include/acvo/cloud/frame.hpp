// One RGB-D frame: colour (8-bit, known channel order), depth in metres, intrinsics, stamp.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"

namespace acvo {

enum class ColorOrder { kRgb, kBgr, kGray };

struct Frame {
  cv::Mat color;  // CV_8UC3 in `order` (kRgb or kBgr), or CV_8UC1 for kGray
  ColorOrder order = ColorOrder::kBgr;
  cv::Mat depth;  // CV_32FC1 metres, 0 = invalid, same size as colour
  Camera camera;
  double stamp = 0.0;  // seconds: the colour image's (a pose is the camera's at this time)
  // The depth image's own stamp when the two streams are not synchronised (a Kinect v1's or a
  // RealSense's colour and depth), 0 when it is the colour's. Odometry moves the depth to the
  // colour's time (OdometryParams::sync_depth).
  double depth_stamp = 0.0;

  // Empty string when the frame is usable; otherwise says what is wrong with it
  // (empty images, wrong types, size mismatch between colour, depth and camera).
  std::string problem() const;
};

// The colour image as 8-bit grey (OpenCV's weights), from its real channel order; the image
// itself when it is grey already.
cv::Mat grayImage(const Frame& frame);

}  // namespace acvo
