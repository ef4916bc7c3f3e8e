// Whole rendered sequences with a person in view (acvo_synth --walker): crossing, walking
// slowly, entering, in view from the start, and a fast camera whose own acceleration must not be
// taken for a person's pull. The second start (OdometryParams::second_start) against one start.
// Bounds are the figures measured here, with a margin.
#include <array>
#include <cstdio>

#include <gtest/gtest.h>

#include "sequence_support.hpp"

namespace acvo {
namespace {

using namespace acvo::test;  // the sequences' helpers (sequence_support.hpp)

// A person crossing a third of the view at 1 m/s (acvo_synth --walker 1, seed 61: in the middle
// of the view for the first 12 frames). The coarse levels' wide kernel spans the camera's motion
// and the person's, and the registration follows the person, 70 mm a frame off; the second
// start from the motion guess, at the finest level alone, holds the still room and scores higher.
TEST(Sequences, APersonCrossingTheViewIsNotMistakenForTheCamerasMotion) {
  synth::SequenceOptions o;
  o.frames = 45;
  o.seed = 61;
  o.walker_speed = 1.0;
  const synth::SynthSequence seq(o);
  Params one_start;
  one_start.odometry.second_start = false;
  // Measured 0.00020 m/s, 0.0044 deg/s with the second start and 0.434, 5.90 with one start
  // (with one keyframe and no window: 0.00032, 0.0060 and 0.469, 6.73; 0.00028, 0.0106 with the
  // photometric term's forward direction alone; the room without the person: 0.0002, 0.005 over
  // 300 frames; with Huber's weight in the direct terms, where the person's residuals kept
  // pulling: 0.00102, 0.0267).
  expectTheModelHelps(seq, groundtruthOf(seq), Params(), one_start, "a second start", "one start",
                      {0.00020, 0.0044}, 50.0);
}

// A person walking at half the pace (acvo_synth --walker 0.5, seed 62: "w62"), over w62's 300
// frames (the camera's path depends on the sequence's length).
synth::SynthSequence slowWalker() {
  synth::SequenceOptions o;
  o.frames = 300;
  o.seed = 62;
  o.walker_speed = 0.5;
  return synth::SynthSequence(o);
}

// w62's person is in view from about frame 189. As it enters, the room outscores it and the second
// start holds the room; from frame 208, filling more of the view, it outscores the room by up to
// 1.42x, and with the plain margin the registration followed it for 30 frames, 35 mm a frame.
// Within kSecondStartMemory of a kept second start the first must score kSecondStartKeptMargin
// times higher. The run starts at frame 170, so that the motion guess knows the camera's velocity
// when the person comes (started at 190, every setting follows the person from its first frame).
TEST(Sequences, ASlowPersonStaysOutOfTheOdometryOnceItWasCaughtPulling) {
  const auto runs = withAndWithoutSecondStart(slowWalker(), 170, 250);
  // Measured 0.000572 m/s, 0.0351 deg/s, with one start 0.891, 12.2 (with one keyframe and no
  // window: 0.00388, 0.1023, with one start 0.907, 12.7; 0.00338, 0.0899 with the photometric
  // term's forward direction alone; with the two directions at equal shares 0.00821, 0.2031: the
  // person, entering, pulled 4-6 mm a frame, under the check; without second_start_check
  // 0.01003, 0.2470: the frame 9 mm off as the person enters; with the plain margin after a kept
  // second start (second_start_memory off) 0.609, 8.53).
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.000572);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.0351);
  EXPECT_GT(runs[1].rpe.trans.rmse, 50.0 * runs[0].rpe.trans.rmse);
}

// The same person's first crossing (w62's frames 0-59). A smooth camera's motion guess misses by
// about 1 mm a frame; the person, entering, pulls the registration 11-19 mm off, under the jerk
// limits (kSecondStartTranslation), so only the check against the camera's usual miss
// (kSecondStartCheckSigmas) runs the second start, which holds the room and scores clearly higher.
TEST(Sequences, APersonEnteringTheViewIsCaughtUnderTheJerkLimits) {
  const auto runs = withAndWithoutSecondStart(slowWalker(), 0, 60);
  // Measured 0.00031 m/s, 0.00815 deg/s, with one start 0.547, 8.28 (with one keyframe and no
  // window: 0.00091, 0.0216, with one start 0.644, 10.6; 0.00259, 0.0564 with the photometric
  // term's forward direction alone; with the jerk limits alone 0.0494, 1.49).
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.00031);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.00815);
  EXPECT_GT(runs[1].rpe.trans.rmse, 50.0 * runs[0].rpe.trans.rmse);
}

// A person already in view when the odometry starts (acvo_synth --walker 1.2 --speed 0.4 --blur
// on --seed 104, 150 frames: the person crosses 1.2 m in front of the camera from frame 0), so no
// velocity tells the camera's motion from the person's: the first registration followed the
// person and the guess then kept it, every frame 55 mm off until it left the view at frame 13
// (over the sequence, 0.1413 m/s).
// The second start from the rest of the points (kRestFraction) finds the room's motion, which
// more of the image agrees with. Frames 0-44.
TEST(Sequences, APersonInViewFromTheStartIsToldFromTheRoom) {
  synth::SequenceOptions o;
  o.frames = 150;
  o.seed = 104;
  o.speed = 0.4;
  o.blur = true;
  o.walker_speed = 1.2;
  const auto runs = withAndWithoutSecondStart(synth::SynthSequence(o), 0, 45);
  // Measured 0.000476 m/s, 0.0278 deg/s (4 second starts, all kept), with one start 0.0749,
  // 0.475 (with one keyframe and no window: 0.00101, 0.0376, with one start 0.0772, 0.544; with
  // the photometric term's forward direction alone 0.00076, 0.0304, the reverse alone 0.00113,
  // 0.0415: the reference's points on the person are sampled in every frame; without the start
  // from the rest of the points 0.412, 2.36: the guess held the person).
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.000476);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.0278);
  EXPECT_GT(runs[1].rpe.trans.rmse, 50.0 * runs[0].rpe.trans.rmse);
  EXPECT_GE(runs[0].second_starts_kept, 1);
}

// A fast hand-held camera's own acceleration makes its motion guess miss by 2-10 mm a frame, and
// on a room without texture the objective has flat ridges: there a second start ends within 0.1%
// of the first's score. The check under the jerk limits must neither run on every such frame nor
// keep those ties (the room at 0.8 m/s, blurred, as scripts/results' fast untextured set: its
// path over 150 frames, frames 0-59).
TEST(Sequences, AFastCamerasOwnAccelerationIsNotTakenForAPull) {
  synth::SequenceOptions o;
  o.frames = 150;
  o.texture = false;
  o.blur = true;
  o.speed = 0.8;
  o.seed = 23;
  const auto runs = withAndWithoutSecondStart(synth::SynthSequence(o), 0, 60);
  // Measured 0.000884 m/s, 0.018 deg/s, as with one start, and 1 second start (its first
  // frames' guess knows no velocity yet), none kept (with one keyframe and no window: 0.00144,
  // 0.0315; 0.00145, 0.0280 with the photometric term's forward direction alone; with the floors
  // alone (5 mm, 0.75 deg, no sigmas) and the plain margin (ties kept) 0.00929, 0.0332; with the
  // floors alone and the 1.1x margin the same figures, at 24 second starts).
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.000884);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.018);
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.05 * runs[1].rpe.trans.rmse);
  EXPECT_EQ(runs[0].second_starts_kept, 0);
  EXPECT_LE(runs[0].second_starts, 3);
}

}  // namespace
}  // namespace acvo
