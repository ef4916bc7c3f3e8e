// Camera trajectories with exactly known poses.
//
// Poses are camera-to-world, optical frame (x right, y down, z forward), smooth functions of
// time that start at MotionOptions::start (defaultStartPose() unless set). Every kind stays
// inside the room and keeps looking into the furnished part (or at the single plane when the
// scene has no structure), at any length of sequence.
//
//   random  sums of three sinusoids (0.15-0.7 Hz at 0.3 m/s, faster for faster motion) per
//           translation axis and per rotation axis of the start's camera frame, seeded
//           frequencies, amplitudes and phases; scaled so that the mean linear speed over the
//           sequence is `speed` and the mean angular speed speed * kAngularPerLinear
//           (0.3 m/s -> 24 deg/s), handheld-like. Offsets from the start stay within 0.5 m
//           per axis and 0.5 rad per rotation-vector component (typically about 0.35 m and
//           25 deg); in the rare sequence that would exceed them, the motion is scaled down
//           and is slower than asked.
//   xyz     back and forth along the camera's x, y, z axes in turn (+-0.2 m), speed `speed`.
//   rpy     rotation back and forth about the camera's x, y, z axes in turn (+-15 deg) at
//           speed * kAngularPerLinear, the optical centre fixed.
//   circle  the optical centre moves on a horizontal circle of radius 0.5 m through the start
//           position at `speed`, the camera always looking at kLookAtTarget (the room centre).
//   still   the start pose at every instant (a camera standing still; `speed` is not used).
//   sway    a camera held still by a hand or on a swaying robot: at the default speed (0.3)
//           +-3 cm sideways at 0.4 Hz, +-2 cm up and down at 0.27 Hz and +-1.5 deg of pan at
//           0.33 Hz about the start; the amplitudes scale with speed / 0.3.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "synth/layout.hpp"

namespace acvo::synth {

enum class MotionKind { kRandom, kXyz, kRpy, kCircle, kStill, kSway };

// "random", "xyz", "rpy", "circle", "still", "sway"; nullopt for anything else.
std::optional<MotionKind> parseMotionKind(const std::string& name);
std::string toString(MotionKind kind);

// Angular speed (rad/s) per unit of linear speed (m/s): 80 deg/s per m/s.
inline constexpr double kAngularPerLinear = 80.0 * M_PI / 180.0;

struct MotionOptions {
  MotionKind kind = MotionKind::kRandom;
  int frames = 300;
  double rate = 30.0;      // Hz
  double speed = 0.3;      // m/s, mean over the sequence (rpy: sets the angular speed only)
  std::uint64_t seed = 1;  // used by `random` only
  Eigen::Isometry3d start = defaultStartPose();
};

// The continuous motion behind a trajectory: poseAt(t) for any t in seconds (t = 0 is the
// start pose), for sub-frame poses (motion blur) or finer sampling than the frame rate.
class Motion {
 public:
  explicit Motion(const MotionOptions& options);  // throws std::invalid_argument on bad options
  Eigen::Isometry3d poseAt(double t) const;
  const MotionOptions& options() const { return options_; }

 private:
  struct Wave {  // amplitude * sin(2 pi frequency t + phase)
    double amplitude, frequency, phase;
  };
  static Eigen::Vector3d sumWaves(const std::vector<Wave> (&waves)[3], double t);
  // The random motion's gains: the mean speeds asked for, within the room.
  void fitGains(const MotionOptions& options);
  Eigen::Isometry3d randomPose(double t) const;
  Eigen::Isometry3d xyzPose(double t) const;
  Eigen::Isometry3d rpyPose(double t) const;
  Eigen::Isometry3d circlePose(double t) const;
  Eigen::Isometry3d swayPose(double t) const;

  MotionOptions options_;
  std::vector<Wave> translation_waves_[3], rotation_waves_[3];  // random motion only
  double translation_gain_ = 1.0, rotation_gain_ = 1.0;         // random motion only
};

// Poses at t_i = i / rate, i = 0 .. frames-1.
std::vector<Eigen::Isometry3d> makeTrajectory(const MotionOptions& options);

}  // namespace acvo::synth
