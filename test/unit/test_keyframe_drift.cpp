// Drift of a camera standing still or swaying for 20 s (600 rendered frames), registered to
// keyframes and to the previous frame on the same frames: keyframes keep it still.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "sequence_support.hpp"

namespace acvo {
namespace {

using namespace acvo::test;  // the sequences' helpers (sequence_support.hpp)

// Drift of a camera that stands still or sways for 20 s (600 frames at 30 Hz, Kinect-like
// noise), registered to keyframes and to the previous frame, on the same frames: the error of
// the last pose and the largest along the way (m, deg).
struct Drift {
  double final_m = 0.0, final_deg = 0.0, worst_m = 0.0, worst_deg = 0.0;
  int keyframes = 0, lost = 0;
};

std::array<Drift, 2> driftOf(synth::MotionKind motion) {
  synth::SequenceOptions o;
  o.frames = 600;
  o.motion = motion;
  const synth::SynthSequence seq(o);
  std::array<Drift, 2> drift;
  std::array<Odometry, 2> odo;
  for (int k = 0; k < 2; ++k) {
    Params p;
    p.odometry.reference = k == 0 ? Reference::kKeyframe : Reference::kPreviousFrame;
    odo[k] = Odometry(p);
    odo[k].reset(seq.poses()[0]);
  }
  for (int i = 0; i < seq.size(); ++i) {
    const Frame f = seq.frame(i).toFrame();
    for (int k = 0; k < 2; ++k) {
      const OdometryResult r = odo[k].process(f);
      const Eigen::Isometry3d e = seq.poses()[std::size_t(i)].inverse() * r.pose;
      Drift& d = drift[std::size_t(k)];
      d.final_m = e.translation().norm();
      d.final_deg = Eigen::AngleAxisd(e.rotation()).angle() * 180.0 / M_PI;
      d.worst_m = std::max(d.worst_m, d.final_m);
      d.worst_deg = std::max(d.worst_deg, d.final_deg);
      d.keyframes += r.new_keyframe;
      d.lost += r.tracking == Tracking::kLost;
    }
  }
  for (int k = 0; k < 2; ++k) {
    const Drift& d = drift[std::size_t(k)];
    std::printf(
        "  %s %-14s after 20 s: %.2f mm %.4f deg (worst %.2f mm %.4f deg), %d keyframes, "
        "%d lost\n",
        synth::toString(motion).c_str(), k == 0 ? "keyframe" : "previous_frame", 1e3 * d.final_m,
        d.final_deg, 1e3 * d.worst_m, d.worst_deg, d.keyframes, d.lost);
  }
  return drift;
}

// A camera standing still gathers no drift against its keyframe (the target: below
// 2 mm and 0.1 deg after 20 s); frame to frame, every frame's noise adds up.
TEST(Sequences, StillCameraDoesNotDriftWithKeyframes) {
  const auto [keyframe, previous] = driftOf(synth::MotionKind::kStill);
  EXPECT_EQ(keyframe.lost, 0);
  EXPECT_EQ(keyframe.keyframes, 1);  // the first frame serves the whole 20 s
  EXPECT_LT(keyframe.final_m, 0.002);
  EXPECT_LT(keyframe.final_deg, 0.1);
  EXPECT_LT(keyframe.worst_m, 0.002);
  EXPECT_GT(previous.final_m, 5.0 * keyframe.final_m);
}

// Swaying by a few centimetres and 1.5 degrees: the keyframe still overlaps, the error stays
// bounded instead of growing with every frame.
TEST(Sequences, SwayingCameraStaysNearItsKeyframes) {
  const auto [keyframe, previous] = driftOf(synth::MotionKind::kSway);
  EXPECT_EQ(keyframe.lost, 0);
  EXPECT_LT(keyframe.final_m, 0.002);
  EXPECT_LT(keyframe.final_deg, 0.1);
  EXPECT_LT(keyframe.worst_m, 0.005);
  EXPECT_GT(previous.final_m, 5.0 * keyframe.final_m);
}

}  // namespace
}  // namespace acvo
