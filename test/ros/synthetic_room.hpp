// A small ray-cast RGB-D scene with known camera motion, for the ROS tests: a closed room
// whose walls carry a random-colour tile texture, with two boxes on the floor. Frames come
// from a camera moving with a constant relative motion, so ground truth is exact.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/camera.hpp"

namespace acvo_test {

struct RgbdImage {
  cv::Mat rgb;    // CV_8UC3, R G B order
  cv::Mat depth;  // CV_32FC1, metres along the optical axis, 0 where nothing was hit
};

// 320x240, fx = fy = 260: small enough that the tests run quickly on a loaded machine.
acvo::Camera testCamera();

// Renders the room seen by a camera at `world_from_camera` (optical frame: x right, y down,
// z forward). Colour is 2x2 supersampled; depth is taken at pixel centres.
RgbdImage renderRoom(const Eigen::Isometry3d& world_from_camera, const acvo::Camera& camera);

// The motion of the camera between consecutive frames (camera k+1 in camera k): 1.5 cm and
// 0.6 degrees, in all axes.
Eigen::Isometry3d frameMotion();

// Camera k in the first camera's frame: frameMotion()^k.
Eigen::Isometry3d cameraPose(int k);

// The first camera in the room (looks at the far wall, a little to one side).
Eigen::Isometry3d worldFromFirstCamera();

}  // namespace acvo_test
