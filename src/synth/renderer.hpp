// Pinhole rendering of a synthetic scene: colour, depth and surface ids, exact or with
// Kinect-like degradations, optionally motion-blurred.
//
// Pixel (u, v) looks along ((u - cx) / fx, (v - cy) / fy, 1) in the optical frame (pixel
// centres at integer coordinates, as acvo::Camera::backProject assumes), and its depth is the
// z of the nearest surface point on that ray. Without noise this is exact: for depth d > 0,
//   pose * camera.backProject(u, v, d)
// is the scene point seen at (u, v) to float rounding (about 1e-7 d), far below the 0.2 mm
// step of a TUM depth PNG. Colour is a function of the surface point only (no lighting),
// so brightness constancy holds exactly between noise-free frames.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"
#include "acvo/cloud/frame.hpp"
#include "synth/kinect_noise.hpp"
#include "synth/scene.hpp"

namespace acvo::synth {

struct RenderOptions {
  Camera camera;       // intrinsics and size; depth_scale sets the noisy depth's unit
  bool noise = false;  // Kinect-like degradations (kinect_noise.hpp) of depth and colour
  KinectNoise kinect;  // their parameters
  // An unregistered colour camera (7-Scenes' colour and depth come from the Kinect's two
  // cameras, paired pixel by pixel as if they were one): its focal lengths are
  // colour_focal_ratio times `camera`'s about the same principal point, its centre
  // colour_baseline metres along the depth camera's x axis, its axes parallel. The colour
  // image is the colour camera's; depth, surfaces and the pose stay the depth camera's.
  double colour_focal_ratio = 1.0;
  double colour_baseline = 0.0;  // m
  // The colour camera's exposure: its image is the scene's colour times this (before the noise
  // and the 8-bit conversion, which saturates), as a camera's auto exposure scales it.
  double brightness = 1.0;
  // The colour camera's vignetting: its image is also darkened by exp(vignetting rho) at each
  // pixel, rho = ((u - cx) / fx)^2 + ((v - cy) / fy)^2 (a lens's falloff towards the corners;
  // 0 = none, -1: 43% darker at a 640x480 TUM camera's corners).
  double vignetting = 0.0;

  bool colourRegistered() const { return colour_focal_ratio == 1.0 && colour_baseline == 0.0; }
  Camera colourCamera() const;                                        // intrinsics
  Eigen::Isometry3d colourPose(const Eigen::Isometry3d& pose) const;  // camera-to-world
};

struct SynthFrame {
  cv::Mat bgr;      // CV_8UC3, BGR (cv::imwrite order)
  cv::Mat depth_m;  // CV_32FC1 metres, 0 = no depth (nothing hit, or dropped by the noise)
  cv::Mat surface;  // CV_32SC1 surface id seen at each pixel (scene.hpp), -1 for none;
                    // from the exact rendering at `pose` (not blurred, not degraded)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera-to-world, optical frame
  double stamp = 0.0;                                      // seconds (set by sequences)
  // The depth's own stamp when the colour was taken at another time (SequenceOptions::
  // colour_delay; `stamp` is then the colour's, `pose` the depth's); 0 when they are one.
  double depth_stamp = 0.0;
  Camera camera;

  // As a core Frame (colour shared, not copied; order BGR).
  Frame toFrame() const;
};

// The exact ray cast at `pose`: colour CV_32FC3 (BGR, [0, 255]), depth CV_32FC1 metres
// (0 where a ray escapes), surface CV_32SC1. Rows are rendered in parallel (TBB).
struct RayCast {
  cv::Mat colour, depth, surface;
};
RayCast rayCast(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& pose);

// One frame at `pose`. `seed` drives the noise (ignored without noise): use a different seed
// per frame. Throws std::invalid_argument for an invalid camera.
SynthFrame render(const Scene& scene, const Eigen::Isometry3d& pose, const RenderOptions& options,
                  std::uint64_t seed = 0);

// Like render(), with motion blur: the colour is the mean of the exact colours at the
// `exposure` poses (e.g. from Motion::poseAt over the shutter time), then noise is added.
// Depth, surfaces and the frame's pose come from `pose` (a structured-light sensor does not
// blur the same way). An empty `exposure` renders without blur.
SynthFrame renderBlurred(const Scene& scene, const Eigen::Isometry3d& pose,
                         const std::vector<Eigen::Isometry3d>& exposure,
                         const RenderOptions& options, std::uint64_t seed = 0);

}  // namespace acvo::synth
