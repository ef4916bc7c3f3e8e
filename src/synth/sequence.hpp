// Synthetic RGB-D sequences: a scene, a trajectory and a renderer put together, in memory
// (frame by frame) or written as a TUM-format folder.
//
// Typical use in a test of another module:
//
//   acvo::synth::SequenceOptions o;
//   o.frames = 2; o.noise = false;
//   acvo::synth::SynthSequence seq(o);
//   auto a = seq.frame(0), b = seq.frame(1);
//   Eigen::Isometry3d b_to_a = a.pose.inverse() * b.pose;   // exact relative motion:
//   // maps points of frame b's optical frame into frame a's.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "synth/trajectory.hpp"

namespace acvo::synth {

// Everything acvo_synth's options say; the defaults are the tool's.
struct SequenceOptions {
  int frames = 300;
  double rate = 30.0;  // Hz
  MotionKind motion = MotionKind::kRandom;
  double speed = 0.3;      // m/s
  std::uint64_t seed = 1;  // scene, trajectory and noise
  bool structure = true;
  bool texture = true;
  bool noise = true;
  bool blur = false;
  int blur_samples = 5;         // sub-frame renders averaged per blurred frame
  double exposure = 0.5;        // shutter time as a fraction of the frame interval (blur)
  double colour_focal_ratio = 1.0;  // an unregistered colour camera (RenderOptions)
  double colour_baseline = 0.0;     // m
  // Colour captured colour_delay seconds after the depth (unsynchronised streams): rendered at
  // the pose of that time and stamped with it in rgb.txt and associations.txt.
  double colour_delay = 0.0;
  // A camera's auto exposure: the colour's brightness at time t is 1 + brightness_swing s(t),
  // s a smooth curve within [-1, 1] (SynthSequence::brightness), up to 3 brightness_swing per
  // second. 0 = constant.
  double brightness_swing = 0.0;
  // The colour camera's vignetting (RenderOptions::vignetting; 0 = none).
  double vignetting = 0.0;
  // The depth noise's correlation length in pixels (KinectNoise::correlation_px; 0 = each
  // pixel's own).
  double depth_noise_correlation = 0.0;
  // The sensor's fixed depth distortion (KinectNoise::distortion_relative; 0 = none), drawn
  // from the seed.
  double depth_distortion = 0.0;
  // A person walking back and forth across the view at this speed (m/s; walkerAt in
  // scene.hpp); 0 = none, the room standing still. A blurred frame (blur) sees the person
  // where it stands at the frame's time: only the camera's motion blurs.
  double walker_speed = 0.0;
  Camera camera;                // TUM default intrinsics, 640x480, depth scale 5000
  double first_stamp = 1000.0;  // seconds; frame i is at first_stamp + i / rate

  SceneOptions sceneOptions() const { return {structure, texture, seed, walker_speed > 0.0}; }
  MotionOptions motionOptions() const;
  RenderOptions renderOptions() const;
};

// The camera scaled to width x height from the TUM default 640x480 intrinsics (focal lengths
// in proportion, principal point at the same place relative to the pixel centres).
Camera scaledDefaultCamera(int width, int height);

class SynthSequence {
 public:
  // Throws std::invalid_argument for bad options (frames < 0, rate <= 0, speed < 0,
  // invalid camera, blur_samples < 1, exposure outside [0, 1], colour_focal_ratio outside
  // [0.5, 2], colour_baseline not within 1 m, colour_delay not under half a frame interval,
  // brightness_swing outside [0, 0.9], vignetting outside [-3, 0], depth_noise_correlation
  // outside [0, 50], depth_distortion outside [0, 0.05], walker_speed outside [0, 5] or with
  // structure off).
  explicit SynthSequence(const SequenceOptions& options);

  int size() const { return options_.frames; }
  double stamp(int i) const { return options_.first_stamp + i / options_.rate; }
  const std::vector<Eigen::Isometry3d>& poses() const { return poses_; }  // camera-to-world
  // Where frame i's colour was taken: poses()[i] unless options().colour_delay.
  Eigen::Isometry3d colourPose(int i) const;
  // The colour's brightness factor at time t seconds after the first frame (1 unless
  // options().brightness_swing): two sines of periods 3.7 and 1.3 s, phases from the seed.
  double brightness(double t) const;
  const Scene& scene() const { return scene_; }  // the room without the walker
  // The world at time t seconds after the first frame: scene() and, with walker_speed, the
  // walker where it is then.
  Scene sceneAt(double t) const;
  const Motion& motion() const { return motion_; }
  const SequenceOptions& options() const { return options_; }

  // Frame i (0 <= i < size()), stamp and pose set. Any order, from any thread; the same i
  // always gives the same images.
  SynthFrame frame(int i) const;

 private:
  SequenceOptions options_;
  Scene scene_;
  Motion motion_;
  std::vector<Eigen::Isometry3d> poses_;
};

// Writes a TUM-format folder: rgb/<stamp>.png (8-bit colour), depth/<stamp>.png (16-bit,
// camera.depth_scale units per metre, 0 = invalid), rgb.txt, depth.txt, associations.txt
// (depth stamps equal rgb stamps), groundtruth.txt (camera-to-world) and camera.yaml.
// Frames are rendered in parallel; `progress(done, total)` is called after each frame, one
// call at a time. Throws std::runtime_error when something cannot be written.
void writeSequence(const std::string& folder, const SequenceOptions& options,
                   const std::function<void(int done, int total)>& progress = {});

// Depth in metres (CV_32FC1, 0 invalid) as a TUM 16-bit PNG image: round(z * depth_scale),
// 0 where invalid or beyond the 16-bit range.
cv::Mat depthToPng16(const cv::Mat& depth_m, double depth_scale);

}  // namespace acvo::synth
