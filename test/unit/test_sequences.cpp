// Whole sequences: RPE over 1 s on synthetic 300-frame sequences (Kinect-like noise) in the
// TUM structure/texture conditions for the default engine (coarse_to_fine) and the paper's A-CVO
// and CVO (paperParams(), cvoParams()); frames missing, blank or with nothing to track, and a
// fast rotation. Bounds are the figures measured here, with a margin. The other
// whole-sequence tests: test_real_sequences (the shared real frames), test_camera_conditions
// (what a real camera does to its images), test_people (a person in view), test_keyframe_drift
// (a camera standing still or swaying).
#include <array>
#include <cstdio>
#include <ostream>
#include <string>

#include <gtest/gtest.h>

#include "sequence_support.hpp"

namespace acvo {
namespace {

using namespace acvo::test;  // the sequences' helpers (sequence_support.hpp)

struct Condition {
  bool structure, texture;
  double max_trans, max_rot_deg;      // bounds for the default engine (m/s, deg/s)
  double paper_trans, paper_rot_deg;  // bounds for the paper's adaptive policy
};

void PrintTo(const Condition& c, std::ostream* os) {
  *os << "structure " << (c.structure ? "on" : "off") << ", texture " << (c.texture ? "on" : "off");
}

class Sequences : public ::testing::TestWithParam<Condition> {};

TEST_P(Sequences, RpeOverOneSecondOnASyntheticSequence) {
  const Condition c = GetParam();
  synth::SequenceOptions o;  // 300 frames, 30 Hz, 0.3 m/s random motion, Kinect-like noise
  o.structure = c.structure;
  o.texture = c.texture;
  const synth::SynthSequence seq(o);
  const Trajectory gt = groundtruthOf(seq);
  const auto runs = runAll(
      seq.size(), [&](int i) { return seq.frame(i).toFrame(); }, gt);
  for (int p = 0; p < 3; ++p) {
    std::printf("  structure %s texture %s %-14s RPE %.5f m/s %.4f deg/s, %d lost\n",
                c.structure ? "on " : "off", c.texture ? "on " : "off", kRunNames[p],
                runs[p].rpe.trans.rmse, runs[p].rpe.rot_deg.rmse, runs[p].lost);
  }
  EXPECT_EQ(runs[0].lost, 0);
  EXPECT_LT(runs[0].rpe.trans.rmse, c.max_trans);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, c.max_rot_deg);
  EXPECT_EQ(runs[1].lost, 0);
  EXPECT_LT(runs[1].rpe.trans.rmse, c.paper_trans);
  EXPECT_LT(runs[1].rpe.rot_deg.rmse, c.paper_rot_deg);
  // The adaptive length-scale is what A-CVO adds: it must not do noticeably worse than CVO's
  // schedule. Measured: better in both on the rooms (by 2x); on the textured plane by 10-20%.
  EXPECT_LE(runs[1].rpe.trans.rmse, 1.15 * runs[2].rpe.trans.rmse);
  EXPECT_LE(runs[1].rpe.rot_deg.rmse, 1.15 * runs[2].rpe.rot_deg.rmse);
  // The default engine is no worse than the paper's on any condition (issue: within 10%).
  EXPECT_LE(runs[0].rpe.trans.rmse, 1.1 * runs[1].rpe.trans.rmse);
  EXPECT_LE(runs[0].rpe.rot_deg.rmse, 1.1 * runs[1].rpe.rot_deg.rmse);
  RecordProperty("default_rpe_trans", std::to_string(runs[0].rpe.trans.rmse));
  RecordProperty("adaptive_rpe_trans", std::to_string(runs[1].rpe.trans.rmse));
  RecordProperty("fixed_rpe_trans", std::to_string(runs[2].rpe.trans.rmse));
}

INSTANTIATE_TEST_SUITE_P(StructureTexture, Sequences,
                         // Measured, default engine (keyframes in a window of 4, max_depth 10,
                         // the last level's direct terms, the dense one on: this renderer draws
                         // its noise per pixel): 0.00021/0.0052, 0.00038/0.0129, 0.00012/0.0041
                         // (with one keyframe and no window: 0.00036/0.0083, 0.00070/0.0176,
                         // 0.00021/0.0063; 0.00038/0.0088, 0.00074/0.0185, 0.00022/0.0066 with
                         // the photometric term's forward direction alone; without the dense
                         // term 0.00055/0.0115, 0.00200/0.0441, 0.00019/0.0054: on a single
                         // plane it pins 3 of 6 directions and outweighs a photometric term
                         // more precise than it says; the kernel alone: 0.0024/0.062,
                         // 0.0047/0.134, 0.0013/0.042; frame to frame it was 0.0078/0.208,
                         // 0.0129/0.300, 0.0032/0.174); paper.yaml (the authors' settings):
                         // 0.0151/0.423, 0.0436/0.981, 0.0052/0.183; cvo.yaml 0.0340/0.855,
                         // 0.0787/1.755, 0.0058/0.232. The default's bounds are 1.3x.
                         ::testing::Values(Condition{true, true, 0.00028, 0.0068, 0.018, 0.51},
                                           Condition{true, false, 0.00050, 0.0168, 0.053, 1.19},
                                           Condition{false, true, 0.00016, 0.0054, 0.0063, 0.22}),
                         [](const auto& info) {
                           return std::string("structure_") +
                                  (info.param.structure ? "on" : "off") + "_texture_" +
                                  (info.param.texture ? "on" : "off");
                         });

TEST(Sequences, NothingToTrackIsLostAndNeverWorseThanStandingStill) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.structure = false;
  o.texture = false;  // a flat, uniformly coloured plane fills the view
  const synth::SynthSequence seq(o);
  const Trajectory gt = groundtruthOf(seq);
  const auto runs = runAll(
      seq.size(), [&](int i) { return seq.frame(i).toFrame(); }, gt);
  Trajectory still = gt;
  for (auto& p : still) p.pose = gt.front().pose;
  const RpeResult zero = computeRpe(gt, still);
  for (const PolicyRun& r : runs) {
    EXPECT_EQ(r.lost, seq.size() - 1);
    EXPECT_LE(r.rpe.trans.rmse, zero.trans.rmse + 1e-9);
    EXPECT_LE(r.rpe.rot_deg.rmse, zero.rot_deg.rmse + 1e-9);
  }
}

// Every other frame missing: 15 Hz from a 30 Hz sequence of 240 frames.
TEST(Sequences, EveryOtherFrameMissingStillTracks) {
  synth::SequenceOptions o;  // 30 Hz, 0.3 m/s random motion, Kinect-like noise
  o.frames = 240;
  const synth::SynthSequence seq(o);
  const Trajectory all = groundtruthOf(seq);
  Trajectory gt;  // the frames that arrive: 15 Hz, twice the motion per registration
  for (int i = 0; i < seq.size(); i += 2) gt.push_back(all[i]);
  const PolicyRun run = runPolicies<1>(
      {Params()}, int(gt.size()), [&](int i) { return seq.frame(2 * i).toFrame(); }, gt)[0];
  std::printf("  every other frame missing: RPE %.5f m/s %.4f deg/s (%zu pairs), %d lost\n",
              run.rpe.trans.rmse, run.rpe.rot_deg.rmse, run.rpe.pairs, run.lost);
  EXPECT_TRUE(allFinite(run.estimate));
  EXPECT_EQ(run.lost, 0);
  // Measured 0.00020 m/s, 0.0046 deg/s (with one keyframe and no window: 0.00033, 0.0075;
  // 0.00039, 0.0092 with the photometric term's forward direction alone; without the dense depth
  // term 0.00031, 0.0065: a textured room, where it outweighs a photometric term more precise
  // than it says; the kernel alone 0.0024, 0.064; frame to frame 0.0063, 0.143); bounds 1.3x.
  EXPECT_LT(run.rpe.trans.rmse, 0.00026);
  EXPECT_LT(run.rpe.rot_deg.rmse, 0.0060);
}

enum class Blank { kNoDepth, kFlatColour };

// A 30 Hz sequence (0.3 m/s random motion, noise) with 1 s of blank frames in the middle: 60
// good frames, 30 blank, 60 good. The blank frames are lost and the pose is held; tracking
// resumes; the error after the blackout stays bounded.
void runBlackout(Blank kind) {
  constexpr int kFrames = 150, kStart = 60, kBlank = 30;
  synth::SequenceOptions o;
  o.frames = kFrames;
  const synth::SynthSequence seq(o);
  const Trajectory gt = groundtruthOf(seq);
  const auto frame_at = [&](int i) {
    Frame f = seq.frame(i).toFrame();
    if (i >= kStart && i < kStart + kBlank) {
      if (kind == Blank::kNoDepth) f.depth.setTo(0.0f);
      if (kind == Blank::kFlatColour) f.color.setTo(cv::Scalar::all(128));
    }
    return f;
  };
  const PolicyRun run = runPolicies<1>({Params()}, kFrames, frame_at, gt)[0];
  const Trajectory& est = run.estimate;
  EXPECT_TRUE(allFinite(est));
  for (int i = 0; i < kStart; ++i) EXPECT_NE(run.tracking[i], Tracking::kLost) << "frame " << i;
  for (int i = kStart; i < kStart + kBlank; ++i) {
    EXPECT_EQ(run.tracking[i], Tracking::kLost) << "blank frame " << i;
    EXPECT_TRUE(est[i].pose.isApprox(est[kStart - 1].pose)) << "pose held at frame " << i;
  }
  // Tracking again within two frames of the blackout's end, and from then on.
  int resumed = kStart + kBlank;
  while (resumed < kFrames &&
         !(run.tracking[resumed] == Tracking::kOk || run.tracking[resumed] == Tracking::kHard)) {
    ++resumed;
  }
  EXPECT_LE(resumed, kStart + kBlank + 2);
  for (int i = resumed; i < kFrames; ++i) {
    EXPECT_NE(run.tracking[i], Tracking::kLost) << "frame " << i << " after the blackout";
  }
  if (resumed >= kFrames - 2) return;
  const auto [blackout_t, blackout_r] = trueMotion(gt, kStart - 1, kStart + kBlank);
  const auto [jump_t, jump_r] = motionError(gt, est, kStart - 1, resumed);
  const auto [across_t, across_r] = motionError(gt, est, kStart - 1, kFrames - 1);
  const Trajectory gt_after(gt.begin() + resumed, gt.end());
  const Trajectory est_after(est.begin() + resumed, est.end());
  const RpeResult rpe_after = computeRpe(gt_after, est_after);
  std::printf(
      "  blackout (%s): resumed at frame %d (the first after it: %d); motion during it %.3f m "
      "%.2f deg, error of the estimate over it %.5f m %.4f deg; error from the last frame before "
      "it to the end (2 s after) %.6f m %.4f deg; RPE after it %.5f m/s %.4f deg/s (%zu pairs)\n",
      kind == Blank::kNoDepth ? "no depth" : "flat colour", resumed, kStart + kBlank, blackout_t,
      blackout_r, jump_t, jump_r, across_t, across_r, rpe_after.trans.rmse, rpe_after.rot_deg.rmse,
      rpe_after.pairs);
  // Measured (both kinds alike: a blank frame never replaces the reference): the first frame
  // after the blackout registers against the last one before it, 0.183 m and 9.6 deg apart,
  // and is judged ok (0.12 mm, 0.0027 deg off); the error from before the blackout to 2 s after
  // it is 0.013 mm, 0.0053 deg; RPE after it 0.00020 m/s, 0.0049 deg/s (with one keyframe and no
  // window: 0.76 mm, 0.0168 deg; 0.00028, 0.0056). Bounds 1.3x, but for the error across in
  // translation: the sum of 2 s of drift that partly cancels, 0.1 mm (an eighth of one
  // keyframe's). (A motion beyond the registration's reach would make that frame lost and the
  // reference restart from it: the error would then be the blackout's motion.)
  EXPECT_LT(across_t, 0.0001);
  EXPECT_LT(across_r, 0.0069);
  EXPECT_LT(rpe_after.trans.rmse, 0.00026);
  EXPECT_LT(rpe_after.rot_deg.rmse, 0.0064);
}

TEST(Sequences, BlackoutOfBlankDepthResumesWithBoundedError) {
  runBlackout(Blank::kNoDepth);
}

TEST(Sequences, BlackoutOfFlatColourResumesWithBoundedError) {
  runBlackout(Blank::kFlatColour);
}

// Lost means lost: a camera turning at more than 90 deg/s (rotation about each axis in turn,
// Kinect-like noise) keeps little overlap between frames, yet every frame is registered and
// kept; the paper's A-CVO judged such frames lost by their low inner product.
TEST(Sequences, FastRotationIsNeverLost) {
  synth::SequenceOptions o;
  o.frames = 90;
  o.motion = synth::MotionKind::kRpy;
  o.speed = 1.2;  // rpy: 80 deg/s per unit of speed
  const synth::SynthSequence seq(o);
  const Trajectory gt = groundtruthOf(seq);
  double angle = 0.0;
  for (int i = 1; i < seq.size(); ++i) angle += trueMotion(gt, i - 1, i).second;
  const double mean_speed = angle / (seq.stamp(seq.size() - 1) - seq.stamp(0));
  ASSERT_GE(mean_speed, 90.0);
  const PolicyRun run = runPolicies<1>(
      {Params()}, seq.size(), [&](int i) { return seq.frame(i).toFrame(); }, gt)[0];
  std::printf("  rotation at %.0f deg/s: RPE %.5f m/s %.4f deg/s, %d lost\n", mean_speed,
              run.rpe.trans.rmse, run.rpe.rot_deg.rmse, run.lost);
  EXPECT_EQ(run.lost, 0);
  for (int i = 1; i < seq.size(); ++i) {
    EXPECT_NE(run.tracking[std::size_t(i)], Tracking::kLost) << "frame " << i;
  }
  // Measured 0.00020 m/s, 0.0055 deg/s (with one keyframe and no window: 0.00040, 0.0099;
  // 0.00044, 0.0113 with the photometric term's forward direction alone; Huber's weight in the
  // direct terms: 0.00055, 0.0138; the kernel alone 0.0023, 0.064; frame to frame 0.0042,
  // 0.111); bounds 1.3x.
  EXPECT_LT(run.rpe.trans.rmse, 0.00026);
  EXPECT_LT(run.rpe.rot_deg.rmse, 0.0072);
}

// A camera turning about each axis in turn at up to 112 deg/s on exact depth (acvo_synth --motion
// rpy --speed 1.4 --noise off --seed 404), whose turn jumps from 0.7 to 5.3 deg between frames 5
// and 7: the motion guess misses frame 7 by 4.6 deg, and the coarse levels took part of the turn's
// image motion for a sideways move, 91 mm, which the finest level kept (the turn itself right to
// 0.001 deg), scoring 0.17 of the last frame's kernel value (under kTurnStartScoreShare). The
// start from that turn with the guess's translation (Odometry::turnStart) scores 4.4x higher and
// is kept. Frames 0-44, against one start (OdometryParams::second_start off).
TEST(Sequences, ATurnsJumpIsNotTakenForASidewaysMove) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.motion = synth::MotionKind::kRpy;
  o.speed = 1.4;
  o.noise = false;
  o.seed = 404;
  const auto runs = withAndWithoutSecondStart(synth::SynthSequence(o), 0, 45);
  // Measured 1.03e-5 m/s, 0.000277 deg/s (6 second starts kept of 16), with one start 0.0638,
  // 0.000796: the first start took the jump for a move. With one keyframe and no window 9.0e-6,
  // 0.00032, with one start 0.0596, 0.00038; with the dense term's points 10 px apart on exact
  // depth as well (exact_depth_grid_stride 10) 0.00019, 0.0081 (3 kept), with one start 0.0641,
  // 0.0005, and without the turn's start (turn_start off) 0.0641, 0.0104.
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 1.03e-5);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.000277);
  EXPECT_GT(runs[1].rpe.trans.rmse, 50.0 * runs[0].rpe.trans.rmse);
  EXPECT_GE(runs[0].second_starts_kept, 1);
}

}  // namespace
}  // namespace acvo
