// A stand-in RGB-D driver for the launch tests: publishes the synthetic room sequence on
// `rgb/image`, `depth/image` and `rgb/camera_info` (remap them to a driver's topics) at a fixed
// rate, going back and forth along the trajectory so it can run indefinitely.
//
// Private parameters: rate (Hz, 10), frames (length of one pass, 30), depth_encoding (32FC1 or
// 16UC1), color_encoding (rgb8), frame_id (camera_rgb_optical_frame), depth_stamp_offset (s, 0).
#include <vector>

#include <ros/ros.h>

#include "synthetic_room.hpp"
#include "test_messages.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "synthetic_camera");
  ros::NodeHandle nh, pnh("~");
  const double rate = pnh.param("rate", 10.0);
  const int frames = std::max(2, pnh.param("frames", 30));
  const std::string depth_encoding = pnh.param<std::string>("depth_encoding", "32FC1");
  const std::string color_encoding = pnh.param<std::string>("color_encoding", "rgb8");
  const std::string frame_id = pnh.param<std::string>("frame_id", "camera_rgb_optical_frame");
  const double depth_offset = pnh.param("depth_stamp_offset", 0.0);

  const acvo::Camera camera = acvo_test::testCamera();
  std::vector<acvo_test::RgbdImage> images;
  for (int k = 0; k < frames; ++k) {
    images.push_back(acvo_test::renderRoom(
        acvo_test::worldFromFirstCamera() * acvo_test::cameraPose(k), camera));
  }
  ros::Publisher rgb_pub = nh.advertise<sensor_msgs::Image>("rgb/image", 5);
  ros::Publisher depth_pub = nh.advertise<sensor_msgs::Image>("depth/image", 5);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 5);
  ROS_INFO("synthetic_camera: %d frames rendered, publishing at %.1f Hz", frames, rate);

  ros::Rate loop(rate);
  for (long n = 0; ros::ok(); ++n) {
    // 0, 1, ..., frames-1, frames-2, ..., 1, 0, 1, ...
    const long period = 2 * (frames - 1);
    const long phase = n % period;
    const int k = static_cast<int>(phase < frames ? phase : period - phase);
    std_msgs::Header header;
    header.stamp = ros::Time::now();
    header.frame_id = frame_id;
    std_msgs::Header depth_header = header;
    depth_header.stamp += ros::Duration(depth_offset);
    rgb_pub.publish(acvo_test::colorMsg(images[k].rgb, color_encoding, header));
    depth_pub.publish(acvo_test::depthMsg(images[k].depth, depth_encoding, depth_header));
    info_pub.publish(acvo_test::infoMsg(camera, header));
    ros::spinOnce();
    loop.sleep();
  }
  return 0;
}
