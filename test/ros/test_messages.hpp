// Builds the camera messages of a synthetic frame in the encodings a driver would send.
#pragma once

#include <limits>
#include <stdexcept>
#include <string>

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <opencv2/imgproc.hpp>

#include "acvo/cloud/camera.hpp"

namespace acvo_test {

// rgb: CV_8UC3 in R G B order; encoding: rgb8, bgr8, rgba8, bgra8 or mono8.
inline sensor_msgs::ImagePtr colorMsg(const cv::Mat& rgb, const std::string& encoding,
                                      const std_msgs::Header& header) {
  namespace enc = sensor_msgs::image_encodings;
  cv::Mat out;
  if (encoding == enc::RGB8)
    out = rgb;
  else if (encoding == enc::BGR8)
    cv::cvtColor(rgb, out, cv::COLOR_RGB2BGR);
  else if (encoding == enc::RGBA8)
    cv::cvtColor(rgb, out, cv::COLOR_RGB2RGBA);
  else if (encoding == enc::BGRA8)
    cv::cvtColor(rgb, out, cv::COLOR_RGB2BGRA);
  else if (encoding == enc::MONO8)
    cv::cvtColor(rgb, out, cv::COLOR_RGB2GRAY);
  else
    throw std::invalid_argument("colorMsg: encoding " + encoding);
  return cv_bridge::CvImage(header, encoding, out).toImageMsg();
}

// depth: CV_32FC1 metres; encoding 32FC1 (metres, invalid = NaN) or 16UC1 (millimetres).
inline sensor_msgs::ImagePtr depthMsg(const cv::Mat& depth, const std::string& encoding,
                                      const std_msgs::Header& header) {
  namespace enc = sensor_msgs::image_encodings;
  cv::Mat out;
  if (encoding == enc::TYPE_32FC1) {
    out = depth.clone();
    out.setTo(std::numeric_limits<float>::quiet_NaN(), depth == 0.0f);
  } else if (encoding == enc::TYPE_16UC1) {
    depth.convertTo(out, CV_16UC1, 1000.0);
  } else {
    throw std::invalid_argument("depthMsg: encoding " + encoding);
  }
  return cv_bridge::CvImage(header, encoding, out).toImageMsg();
}

inline sensor_msgs::CameraInfoPtr infoMsg(const acvo::Camera& c, const std_msgs::Header& header) {
  auto info = boost::make_shared<sensor_msgs::CameraInfo>();
  info->header = header;
  info->width = c.width;
  info->height = c.height;
  info->distortion_model = "plumb_bob";
  info->D.assign(5, 0.0);
  info->K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  info->R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info->P = {c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return info;
}

}  // namespace acvo_test
