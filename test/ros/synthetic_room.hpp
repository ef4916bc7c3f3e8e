// RGB-D frames with exactly known motion for the ROS tests: the procedural room of the
// acvo_synthetic library (src/synth), noise-free, seen by a camera moving with a constant
// relative motion, so that ground truth is exact and every frame can be made on demand.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"

namespace acvo_test {

struct RgbdImage {
  cv::Mat rgb;    // CV_8UC3, R G B order
  cv::Mat depth;  // CV_32FC1, metres along the optical axis, 0 where nothing was hit
};

// 320x240, the TUM default intrinsics scaled: small frames keep the tests quick on a loaded
// machine.
acvo::Camera testCamera();

// The room seen by a camera at `world_from_camera` (optical frame: x right, y down, z forward).
// colour_focal_ratio != 1: the colour from an unregistered camera with that many times the
// focal length (acvo::synth::RenderOptions), as a driver's raw depth would be paired with it.
RgbdImage renderRoom(const Eigen::Isometry3d& world_from_camera, const acvo::Camera& camera,
                     double colour_focal_ratio = 1.0);

// The motion of the camera between consecutive frames (camera k+1 in camera k): 1.5 cm and
// 0.6 degrees, in all axes (0.45 m/s and 18 deg/s at 30 Hz, a brisk hand-held motion).
Eigen::Isometry3d frameMotion();

// Camera k in the first camera's frame: frameMotion()^k.
Eigen::Isometry3d cameraPose(int k);

// The first camera in the room (the generator's start pose, looking at the furniture).
Eigen::Isometry3d worldFromFirstCamera();

}  // namespace acvo_test
