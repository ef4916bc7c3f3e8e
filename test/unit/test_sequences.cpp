// Whole sequences: RPE over 1 s on synthetic 300-frame sequences (Kinect-like noise) in the
// TUM structure/texture conditions and on the shared real Kinect frames, for both length-scale
// policies. Bounds are the measured figures with a margin (README, "Accuracy").
#include <array>
#include <cstdio>

#include <gtest/gtest.h>

#include "acvo/evaluation.hpp"
#include "acvo/odometry.hpp"
#include "acvo/tum.hpp"
#include "synth/sequence.hpp"
#include "test_support.hpp"

namespace acvo {
namespace {

struct PolicyRun {
  RpeResult rpe;
  int lost = 0;
};

// Runs odometry with both policies over the same frames (rendered once).
template <typename FrameAt>
std::array<PolicyRun, 2> runBoth(int frames, FrameAt frame_at, const Trajectory& groundtruth) {
  std::array<PolicyRun, 2> runs;
  std::array<Odometry, 2> odo;
  std::array<Trajectory, 2> est;
  for (int p = 0; p < 2; ++p) {
    Params params;
    params.solver.ell_policy = p == 0 ? EllPolicy::kAdaptive : EllPolicy::kFixedSchedule;
    odo[p] = Odometry(params);
    odo[p].reset(groundtruth.front().pose);
  }
  for (int i = 0; i < frames; ++i) {
    const Frame f = frame_at(i);
    for (int p = 0; p < 2; ++p) {
      const OdometryResult r = odo[p].process(f);
      runs[p].lost += r.tracking == Tracking::kLost;
      est[p].push_back({groundtruth[i].stamp_text, groundtruth[i].stamp, r.pose});
    }
  }
  for (int p = 0; p < 2; ++p) runs[p].rpe = computeRpe(groundtruth, est[p]);
  return runs;
}

Trajectory groundtruthOf(const synth::SynthSequence& seq) {
  Trajectory gt;
  for (int i = 0; i < seq.size(); ++i) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", seq.stamp(i));
    gt.push_back({text, seq.stamp(i), seq.poses()[i]});
  }
  return gt;
}

struct Condition {
  bool structure, texture;
  double max_trans, max_rot_deg;  // bounds for the adaptive policy (m/s, deg/s)
};

class Sequences : public ::testing::TestWithParam<Condition> {};

TEST_P(Sequences, RpeOverOneSecondOnASyntheticSequence) {
  const Condition c = GetParam();
  synth::SequenceOptions o;  // 300 frames, 30 Hz, 0.3 m/s random motion, Kinect-like noise
  o.structure = c.structure;
  o.texture = c.texture;
  const synth::SynthSequence seq(o);
  const Trajectory gt = groundtruthOf(seq);
  const auto runs = runBoth(seq.size(), [&](int i) { return seq.frame(i).toFrame(); }, gt);
  for (int p = 0; p < 2; ++p) {
    std::printf("  structure %s texture %s %-14s RPE %.4f m/s %.3f deg/s, %d lost\n",
                c.structure ? "on " : "off", c.texture ? "on " : "off",
                p == 0 ? "adaptive" : "fixed_schedule", runs[p].rpe.trans.rmse,
                runs[p].rpe.rot_deg.rmse, runs[p].lost);
  }
  EXPECT_EQ(runs[0].lost, 0);
  EXPECT_LT(runs[0].rpe.trans.rmse, c.max_trans);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, c.max_rot_deg);
  // The adaptive length-scale is what A-CVO adds: it must not do worse than CVO's schedule.
  EXPECT_LE(runs[0].rpe.trans.rmse, runs[1].rpe.trans.rmse);
  EXPECT_LE(runs[0].rpe.rot_deg.rmse, runs[1].rpe.rot_deg.rmse);
  RecordProperty("adaptive_rpe_trans", std::to_string(runs[0].rpe.trans.rmse));
  RecordProperty("fixed_rpe_trans", std::to_string(runs[1].rpe.trans.rmse));
}

INSTANTIATE_TEST_SUITE_P(StructureTexture, Sequences,
                         // Measured (adaptive): 0.0083/0.240, 0.0229/0.544, 0.0046/0.167.
                         ::testing::Values(Condition{true, true, 0.015, 0.45},
                                           Condition{true, false, 0.04, 1.0},
                                           Condition{false, true, 0.01, 0.35}),
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
  const auto runs = runBoth(seq.size(), [&](int i) { return seq.frame(i).toFrame(); }, gt);
  Trajectory still = gt;
  for (auto& p : still) p.pose = gt.front().pose;
  const RpeResult zero = computeRpe(gt, still);
  for (const PolicyRun& r : runs) {
    EXPECT_EQ(r.lost, seq.size() - 1);
    EXPECT_LE(r.rpe.trans.rmse, zero.trans.rmse + 1e-9);
    EXPECT_LE(r.rpe.rot_deg.rmse, zero.rot_deg.rmse + 1e-9);
  }
}

TEST(Sequences, RpeOnRealKinectFrames) {
  const auto shared = test::sharedDataDir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data not present";
  const TumDataset data((shared / "kitchen7s_dev").string());
  ASSERT_TRUE(data.groundtruth());
  Trajectory gt;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto& e = data.frames()[i].rgb;
    // Ground truth at the frame stamps (this dataset has one pose per frame).
    gt.push_back({e.stamp_text, e.stamp, (*data.groundtruth())[i].pose});
  }
  const auto runs =
      runBoth(int(data.size()), [&](int i) { return data.loadFrame(std::size_t(i)); }, gt);
  for (int p = 0; p < 2; ++p) {
    std::printf("  kitchen7s_dev %-14s RPE %.4f m/s %.3f deg/s, %d lost\n",
                p == 0 ? "adaptive" : "fixed_schedule", runs[p].rpe.trans.rmse,
                runs[p].rpe.rot_deg.rmse, runs[p].lost);
  }
  // Measured 0.060 m/s, 4.40 deg/s (adaptive). 7-Scenes colour and depth come from two
  // unregistered cameras: the labels sit beside their points, which costs accuracy here.
  EXPECT_EQ(runs[0].lost, 0);
  EXPECT_LT(runs[0].rpe.trans.rmse, 0.08);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 5.5);
}

}  // namespace
}  // namespace acvo
