// Whole sequences: RPE over 1 s on synthetic 300-frame sequences (Kinect-like noise) in the
// TUM structure/texture conditions and on the shared real Kinect frames, for the default engine
// (coarse_to_fine) and the paper's A-CVO and CVO (paperParams(), cvoParams()). Bounds are the
// measured figures with a margin (docs/accuracy.md).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <utility>
#include <vector>

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
  Trajectory estimate;             // one pose per frame given
  std::vector<Tracking> tracking;  // the engine's judgement of each frame
  // frames whose finest level ran again from the guess, or that ran the start from the rest of
  // the points (OdometryResult::second_start)
  int second_starts = 0;
  int second_starts_kept = 0;      // ... and kept that result
};

// Runs odometry with each setting over the same frames (rendered once); frame i is compared
// with groundtruth[i].
template <std::size_t N, typename FrameAt>
std::array<PolicyRun, N> runPolicies(const std::array<Params, N>& settings, int frames,
                                     FrameAt frame_at, const Trajectory& groundtruth) {
  std::array<PolicyRun, N> runs;
  std::array<Odometry, N> odo;
  for (std::size_t p = 0; p < N; ++p) {
    odo[p] = Odometry(settings[p]);
    odo[p].reset(groundtruth.front().pose);
  }
  for (int i = 0; i < frames; ++i) {
    const Frame f = frame_at(i);
    for (std::size_t p = 0; p < N; ++p) {
      const OdometryResult r = odo[p].process(f);
      runs[p].lost += r.tracking == Tracking::kLost;
      runs[p].tracking.push_back(r.tracking);
      runs[p].second_starts += r.second_start;
      runs[p].second_starts_kept += r.second_start_kept;
      runs[p].estimate.push_back({groundtruth[i].stamp_text, groundtruth[i].stamp, r.pose});
    }
  }
  for (std::size_t p = 0; p < N; ++p) runs[p].rpe = computeRpe(groundtruth, runs[p].estimate);
  return runs;
}

// The default engine, then the paper's adaptive and fixed-schedule policies.
template <typename FrameAt>
std::array<PolicyRun, 3> runAll(int frames, FrameAt frame_at, const Trajectory& groundtruth) {
  return runPolicies<3>({Params(), paperParams(), cvoParams()}, frames, frame_at, groundtruth);
}
const char* const kRunNames[] = {"coarse_to_fine", "adaptive", "fixed_schedule"};

Trajectory groundtruthOf(const synth::SynthSequence& seq) {
  Trajectory gt;
  for (int i = 0; i < seq.size(); ++i) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", seq.stamp(i));
    gt.push_back({text, seq.stamp(i), seq.poses()[i]});
  }
  return gt;
}

// A model of the camera against the default with it turned off (`without`), over a rendered
// sequence: both printed as "  <name>: RPE ...", neither loses a frame; the default within 1.3x
// of its measured figures (`trans` m/s, `rot` deg/s) and `without` at least `factor` times worse
// in both. `with` is the default, or the default with what the comparison leaves aside.
struct Figures {
  double trans, rot;
};
void expectTheModelHelps(const synth::SynthSequence& seq, const Trajectory& gt, const Params& with,
                         const Params& without, const char* name, const char* name_without,
                         Figures measured, double factor) {
  const auto runs = runPolicies<2>(
      {with, without}, seq.size(), [&](int i) { return seq.frame(i).toFrame(); }, gt);
  for (int p = 0; p < 2; ++p) {
    std::printf("  %s: RPE %.5f m/s %.4f deg/s, %d lost\n", p == 0 ? name : name_without,
                runs[p].rpe.trans.rmse, runs[p].rpe.rot_deg.rmse, runs[p].lost);
    EXPECT_EQ(runs[p].lost, 0);
  }
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * measured.trans);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * measured.rot);
  EXPECT_GT(runs[1].rpe.trans.rmse, factor * runs[0].rpe.trans.rmse);
  EXPECT_GT(runs[1].rpe.rot_deg.rmse, factor * runs[0].rpe.rot_deg.rmse);
}

// The default without the dense depth term, for the models of the colour: with the renderer's
// noise drawn per pixel the dense term carries much of the motion on its own (docs/accuracy.md,
// thirteenth round), and what a model of the colour gains is measured with the colour leading.
Params colourModelBase() {
  Params p;
  p.coarse_to_fine.dense_point_to_plane = false;
  return p;
}

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
                         // Measured, default engine (keyframes, max_depth 10, the last
                         // level's direct terms, the dense one on: this renderer draws its
                         // noise per pixel): 0.00038/0.0088, 0.00074/0.0185, 0.00022/0.0066
                         // (without the dense term 0.00055/0.0115, 0.00200/0.0441,
                         // 0.00019/0.0054: on a single plane it pins 3 of 6 directions and
                         // outweighs a photometric term more precise than it says,
                         // docs/accuracy.md thirteenth round; the kernel alone: 0.0024/0.062,
                         // 0.0047/0.134, 0.0013/0.042; frame to frame it was 0.0078/0.208,
                         // 0.0129/0.300, 0.0032/0.174); paper.yaml (the authors' settings):
                         // 0.0151/0.423, 0.0436/0.981, 0.0052/0.183; cvo.yaml 0.0340/0.855,
                         // 0.0787/1.755, 0.0058/0.232. The default's bounds are 1.3x.
                         ::testing::Values(Condition{true, true, 0.00049, 0.0114, 0.018, 0.51},
                                           Condition{true, false, 0.00096, 0.0241, 0.053, 1.19},
                                           Condition{false, true, 0.00029, 0.0086, 0.0063, 0.22}),
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

bool allFinite(const Trajectory& t) {
  for (const auto& p : t) {
    if (!p.pose.matrix().allFinite()) return false;
  }
  return true;
}

// Error of the estimated motion from pose a to pose b against the true one: (m, deg).
std::pair<double, double> motionError(const Trajectory& gt, const Trajectory& est, int a, int b) {
  const Eigen::Isometry3d e =
      (est[a].pose.inverse() * est[b].pose) * (gt[a].pose.inverse() * gt[b].pose).inverse();
  return {e.translation().norm(), Eigen::AngleAxisd(e.rotation()).angle() * 180.0 / M_PI};
}

// The true motion from pose a to pose b: (m, deg).
std::pair<double, double> trueMotion(const Trajectory& gt, int a, int b) {
  const Eigen::Isometry3d m = gt[a].pose.inverse() * gt[b].pose;
  return {m.translation().norm(), Eigen::AngleAxisd(m.rotation()).angle() * 180.0 / M_PI};
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
  // Measured 0.00039 m/s, 0.0092 deg/s (without the dense depth term 0.00031, 0.0065: a
  // textured room, where it outweighs a photometric term more precise than it says,
  // docs/accuracy.md thirteenth round; the kernel alone 0.0024, 0.064; frame to frame 0.0063,
  // 0.143); bounds 1.3x.
  EXPECT_LT(run.rpe.trans.rmse, 0.00051);
  EXPECT_LT(run.rpe.rot_deg.rmse, 0.0120);
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
      "it to the end (2 s after) %.5f m %.4f deg; RPE after it %.5f m/s %.4f deg/s (%zu pairs)\n",
      kind == Blank::kNoDepth ? "no depth" : "flat colour", resumed, kStart + kBlank, blackout_t,
      blackout_r, jump_t, jump_r, across_t, across_r, rpe_after.trans.rmse, rpe_after.rot_deg.rmse,
      rpe_after.pairs);
  // Measured (both kinds alike: a blank frame never replaces the reference): the first frame
  // after the blackout registers against the last one before it, 0.183 m and 9.6 deg apart,
  // and is judged ok (0.18 mm, 0.0041 deg off); the error from before the blackout to 2 s after
  // it is 0.69 mm, 0.0179 deg; RPE after it 0.00024 m/s, 0.0065 deg/s (the kernel alone: 0.026 m,
  // 0.65 deg; 0.0103 m/s, 0.309 deg/s). Bounds 1.3x. (A motion beyond the registration's reach
  // would make that frame lost and the reference restart from it: the error would then be the
  // blackout's motion.)
  EXPECT_LT(across_t, 0.0009);
  EXPECT_LT(across_r, 0.0233);
  EXPECT_LT(rpe_after.trans.rmse, 0.00031);
  EXPECT_LT(rpe_after.rot_deg.rmse, 0.0085);
}

TEST(Sequences, BlackoutOfBlankDepthResumesWithBoundedError) {
  runBlackout(Blank::kNoDepth);
}

TEST(Sequences, BlackoutOfFlatColourResumesWithBoundedError) {
  runBlackout(Blank::kFlatColour);
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
  const auto frame_at = [&](int i) { return data.loadFrame(std::size_t(i)); };
  const auto runs = runAll(int(data.size()), frame_at, gt);
  Params denser;
  denser.selection.reference_density = 2.0;
  const PolicyRun dense = runPolicies<1>({denser}, int(data.size()), frame_at, gt)[0];
  for (int p = 0; p < 3; ++p) {
    std::printf("  kitchen7s_dev %-14s RPE %.4f m/s %.3f deg/s, %d lost\n", kRunNames[p],
                runs[p].rpe.trans.rmse, runs[p].rpe.rot_deg.rmse, runs[p].lost);
  }
  std::printf("  kitchen7s_dev reference_density 2 RPE %.4f m/s %.3f deg/s, %d lost\n",
              dense.rpe.trans.rmse, dense.rpe.rot_deg.rmse, dense.lost);
  // Measured 0.0321 m/s, 1.868 deg/s (default: its colour found unregistered and resampled,
  // docs/accuracy.md, fifteenth round); paper.yaml 0.0628 m/s, 4.479 deg/s; cvo.yaml 0.0893,
  // 5.474. Bounds 1.1x. 7-Scenes colour and depth come from two unregistered cameras.
  EXPECT_EQ(runs[0].lost, 0);
  EXPECT_LT(runs[0].rpe.trans.rmse, 0.0353);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 2.05);
  EXPECT_EQ(runs[1].lost, 0);
  EXPECT_LT(runs[1].rpe.trans.rmse, 0.07);
  EXPECT_LT(runs[1].rpe.rot_deg.rmse, 5.0);
  EXPECT_EQ(runs[2].lost, 0);
  // A keyframe cloud twice as dense as the registered ones (selection.reference_density 2):
  // measured 0.0236 m/s, 1.669 deg/s, 0.73x and 0.89x the default's. Bounds 1.1x.
  EXPECT_EQ(dense.lost, 0);
  EXPECT_LT(dense.rpe.trans.rmse, 0.026);
  EXPECT_LT(dense.rpe.rot_deg.rmse, 1.83);
  EXPECT_LT(dense.rpe.trans.rmse, 0.85 * runs[0].rpe.trans.rmse);
}

// TUM fr3/teddy (200 frames, hand-held, up to 100 deg/s) with motion-capture ground truth: the
// default engine within a margin of its measured figures, nothing lost, and well below the
// drift of the same engine registering frame to frame. (OpenCV's RgbdOdometry set up as its
// TUM sample, at 10 m, does better here: 0.0104 m/s, 0.496 deg/s; docs/accuracy.md.)
TEST(Sequences, RealHandHeldMotionIsTrackedWithoutLossOrDrift) {
  const auto shared = test::sharedDataDir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data not present";
  const TumDataset data((shared / "tum_fr3_teddy200").string());
  ASSERT_TRUE(data.groundtruth());
  const Trajectory& gt = *data.groundtruth();
  // Start at the ground-truth pose nearest the first frame (motion capture runs at 100 Hz).
  const double t0 = data.frames().front().rgb.stamp;
  const auto nearest = std::min_element(gt.begin(), gt.end(), [t0](const auto& a, const auto& b) {
    return std::abs(a.stamp - t0) < std::abs(b.stamp - t0);
  });
  // The default (keyframes), the same engine frame to frame, and keyframe clouds twice as dense
  // as the registered ones, on the same frames.
  std::array<Odometry, 3> odo;
  Params previous_frame;
  previous_frame.odometry.reference = Reference::kPreviousFrame;
  odo[1] = Odometry(previous_frame);
  Params denser;
  denser.selection.reference_density = 2.0;
  odo[2] = Odometry(denser);
  std::array<Trajectory, 3> est;
  std::array<int, 3> lost = {0, 0, 0};
  for (int k = 0; k < 3; ++k) odo[k].reset(nearest->pose);
  for (std::size_t i = 0; i < data.size(); ++i) {
    const Frame frame = data.loadFrame(i);
    const auto& e = data.frames()[i].rgb;
    for (int k = 0; k < 3; ++k) {
      const OdometryResult r = odo[k].process(frame);
      lost[k] += r.tracking == Tracking::kLost;
      est[k].push_back({e.stamp_text, e.stamp, r.pose});
    }
  }
  const RpeResult rpe = computeRpe(gt, est[0]);
  const double ate = computeAte(gt, est[0]).trans.rmse;
  const double ate_previous = computeAte(gt, est[1]).trans.rmse;
  std::printf(
      "  tum_fr3_teddy200 default RPE %.4f m/s %.3f deg/s, ATE %.4f m (frame to frame "
      "%.4f m), %d lost\n",
      rpe.trans.rmse, rpe.rot_deg.rmse, ate, ate_previous, lost[0]);
  // Measured 0.0059 m/s, 0.470 deg/s; ATE 0.0061 m against 0.0154 m frame to frame (the kernel
  // alone: 0.0086, 0.579, ATE 0.0105; max_depth 4: 0.0159, 1.066, ATE 0.0185). Bounds 1.3x.
  EXPECT_EQ(lost[0], 0);
  EXPECT_LT(rpe.trans.rmse, 0.0077);
  EXPECT_LT(rpe.rot_deg.rmse, 0.611);
  // Keyframes against drift: at most 0.7 of the frame-to-frame ATE (the target).
  EXPECT_LT(ate, 0.7 * ate_previous);
  // The denser keyframe clouds (selection.reference_density 2): measured 0.0054 m/s, 0.459
  // deg/s. Bounds 1.1x.
  const RpeResult dense = computeRpe(gt, est[2]);
  std::printf("  tum_fr3_teddy200 reference_density 2 RPE %.4f m/s %.3f deg/s, %d lost\n",
              dense.trans.rmse, dense.rot_deg.rmse, lost[2]);
  EXPECT_EQ(lost[2], 0);
  EXPECT_LT(dense.trans.rmse, 0.0060);
  EXPECT_LT(dense.rot_deg.rmse, 0.506);
}

// The paper's A-CVO (config/paper.yaml) and CVO (config/cvo.yaml) against the authors' public
// code, built and run on the same 193 teddy frames: A-CVO 0.0957 m/s, 5.78 deg/s; CVO 0.111 m/s,
// 6.45 deg/s. Each must be within 5% of those in both, nothing lost.
TEST(Sequences, PaperConfigsReproduceTheAuthorsCodeOnTeddy) {
  const auto shared = test::sharedDataDir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data not present";
  const TumDataset data((shared / "tum_fr3_teddy200").string());
  ASSERT_TRUE(data.groundtruth());
  const Trajectory& gt = *data.groundtruth();
  const double t0 = data.frames().front().rgb.stamp;
  const auto nearest = std::min_element(gt.begin(), gt.end(), [t0](const auto& a, const auto& b) {
    return std::abs(a.stamp - t0) < std::abs(b.stamp - t0);
  });
  std::array<Odometry, 2> odo = {Odometry(paperParams()), Odometry(cvoParams())};
  std::array<Trajectory, 2> est;
  std::array<int, 2> lost = {0, 0};
  for (int k = 0; k < 2; ++k) odo[k].reset(nearest->pose);
  for (std::size_t i = 0; i < data.size(); ++i) {
    const Frame frame = data.loadFrame(i);
    const auto& e = data.frames()[i].rgb;
    for (int k = 0; k < 2; ++k) {
      const OdometryResult r = odo[k].process(frame);
      lost[k] += r.tracking == Tracking::kLost;
      est[k].push_back({e.stamp_text, e.stamp, r.pose});
    }
  }
  const char* names[] = {"paper.yaml (A-CVO)", "cvo.yaml (CVO)"};
  const double authors[2][2] = {{0.0957, 5.78}, {0.111, 6.45}};
  for (int k = 0; k < 2; ++k) {
    const RpeResult rpe = computeRpe(gt, est[k]);
    const double rt = rpe.trans.rmse / authors[k][0], rr = rpe.rot_deg.rmse / authors[k][1];
    std::printf(
        "  tum_fr3_teddy200 %-18s RPE %.4f m/s %.3f deg/s (%.3f / %.3f of the authors' "
        "code), %d lost\n",
        names[k], rpe.trans.rmse, rpe.rot_deg.rmse, rt, rr, lost[k]);
    // Measured: A-CVO 0.0955 / 5.943 (0.998 / 1.028); CVO 0.1068 / 6.164 (0.962 / 0.956).
    EXPECT_EQ(lost[k], 0) << names[k];
    EXPECT_NEAR(rt, 1.0, 0.05) << names[k];
    EXPECT_NEAR(rr, 1.0, 0.05) << names[k];
  }
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
  // Measured 0.00044 m/s, 0.0113 deg/s (Huber's weight in the direct terms: 0.00055, 0.0138; the
  // kernel alone 0.0023, 0.064; frame to frame 0.0042, 0.111); bounds 1.3x.
  EXPECT_LT(run.rpe.trans.rmse, 0.00057);
  EXPECT_LT(run.rpe.rot_deg.rmse, 0.0147);
}

// Colour taken 12 ms after the depth (unsynchronised streams, as a Kinect v1's or a
// RealSense's), the camera at 0.5 m/s: the poses are the colour's, and each frame's depth is
// moved to the colour's time (OdometryParams::sync_depth) by the last frame-to-frame motion, then
// by the velocity filter's blend of that and the frame's own. Without it each point's colour is
// of another instant than its position.
TEST(Sequences, UnsynchronisedColourAndDepthAreBroughtToOneInstant) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.seed = 2;
  o.speed = 0.5;
  o.colour_delay = 0.012;
  const synth::SynthSequence seq(o);
  Trajectory gt;  // at the colour's stamps
  for (int i = 0; i < seq.size(); ++i) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", seq.stamp(i) + o.colour_delay);
    gt.push_back({text, seq.stamp(i) + o.colour_delay, seq.colourPose(i)});
  }
  Params unsynced;
  unsynced.odometry.sync_depth = false;
  // Measured 0.00036 m/s, 0.0078 deg/s moved and 0.01509, 0.5213 as it came (150 frames of the
  // same motion without the delay: 0.0003, 0.008; moved by the last frame's motion alone 0.00055,
  // 0.0079; by the frame's own alone 0.00041, 0.0083).
  expectTheModelHelps(seq, gt, Params(), unsynced, "depth moved to the colour's time",
                      "depth as it came", {0.00036, 0.0078}, 3.0);
}

// A camera's auto exposure: the colour's brightness swings by up to +-20%, 2% a frame
// (SequenceOptions::brightness_swing). The photometric term compares grey values at the gain it
// measures between each frame and its reference (CoarseToFineParams::photometric_gain); without
// it every grey value is off by the gain, and the motion with it.
TEST(Sequences, AutoExposureIsMeasuredNotMistakenForMotion) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.brightness_swing = 0.2;
  const synth::SynthSequence seq(o);
  Params as_they_are = colourModelBase();
  as_they_are.coarse_to_fine.photometric_gain = false;
  // Measured (the dense term off: colourModelBase) 0.00039 m/s, 0.0074 deg/s at the gain and
  // 0.00117, 0.0255 as they are (150 frames of this room without the swing, scripts/results:
  // 0.0004, 0.008).
  expectTheModelHelps(seq, groundtruthOf(seq), colourModelBase(), as_they_are,
                      "grey values at the measured gain", "grey values as they are",
                      {0.00039, 0.0074}, 2.0);
}

// Motion blur where the colour has no texture: every colour edge is a depth edge, and a blurred
// edge gives the points beside it, on either surface, the other surface's colour. The default
// leaves out the points whose smear over the exposure (CoarseToFineParams::exposure_time, as
// predicted from the last motion) crosses a depth edge; with sharp images assumed they pull
// the motion.
TEST(Sequences, MotionBlurOverDepthEdgesIsNotMistakenForMotion) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.texture = false;
  o.blur = true;
  const synth::SynthSequence seq(o);
  Params sharp = colourModelBase();
  sharp.coarse_to_fine.exposure_time = 0.0;
  // Measured (the dense term off: colourModelBase) 0.00142 m/s, 0.0257 deg/s at the default
  // 0.016 s (the renderer blurs over 1/60 s) and 0.00361, 0.0823 with sharp images assumed.
  expectTheModelHelps(seq, groundtruthOf(seq), colourModelBase(), sharp,
                      "blur over the exposure time", "blur assumed away", {0.00142, 0.0257}, 2.0);
}

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
  // Measured 0.00028 m/s, 0.0106 deg/s with the second start and 0.467, 6.67 with one start
  // (the room without the person: 0.0002, 0.005 over 300 frames, docs/accuracy.md; with Huber's
  // weight in the direct terms, where the person's residuals kept pulling: 0.00102, 0.0267).
  expectTheModelHelps(seq, groundtruthOf(seq), Params(), one_start, "a second start",
                      "one start", {0.00028, 0.0106}, 50.0);
}

// Frames [first, end) of a rendered sequence with the default settings and with one start
// (OdometryParams::second_start off), each printed; neither may lose a frame.
std::array<PolicyRun, 2> withAndWithoutSecondStart(const synth::SynthSequence& seq, int first,
                                                   int end) {
  const Trajectory all = groundtruthOf(seq);
  const Trajectory gt(all.begin() + first, all.begin() + end);
  Params one_start;
  one_start.odometry.second_start = false;
  auto runs = runPolicies<2>(
      {Params(), one_start}, int(gt.size()), [&](int i) { return seq.frame(first + i).toFrame(); },
      gt);
  for (int p = 0; p < 2; ++p) {
    std::printf("  %s: RPE %.5f m/s %.4f deg/s, %d lost, %d second starts (%d kept)\n",
                p == 0 ? "default" : "one start", runs[p].rpe.trans.rmse,
                runs[p].rpe.rot_deg.rmse, runs[p].lost, runs[p].second_starts,
                runs[p].second_starts_kept);
    EXPECT_EQ(runs[p].lost, 0);
  }
  return runs;
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
  // Measured 0.00338 m/s, 0.0899 deg/s (0.01003, 0.2470 before the check below the jerk limits
  // caught the frame 9 mm off as the person enters); with the plain margin after a kept second
  // start 0.609, 8.53, and with one start 0.907, 12.7.
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.00338);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.0899);
  EXPECT_GT(runs[1].rpe.trans.rmse, 50.0 * runs[0].rpe.trans.rmse);
}

// The same person's first crossing (w62's frames 0-59). A smooth camera's motion guess misses by
// about 1 mm a frame; the person, entering, pulls the registration 11-19 mm off, under the jerk
// limits (kSecondStartTranslation), so only the check against the camera's usual miss
// (kSecondStartCheckSigmas) runs the second start, which holds the room and scores clearly higher.
TEST(Sequences, APersonEnteringTheViewIsCaughtUnderTheJerkLimits) {
  const auto runs = withAndWithoutSecondStart(slowWalker(), 0, 60);
  // Measured 0.00259 m/s, 0.0564 deg/s; with the jerk limits alone 0.0494, 1.49; with one start
  // 0.670, 11.1.
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.00259);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.0564);
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
  // Measured 0.00076 m/s, 0.0304 deg/s (4 second starts, all kept); without the start from the
  // rest of the points 0.412, 2.36 (the guess held the person), with one start 0.0772, 0.544.
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.00076);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.0304);
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
  // Measured 0.00145 m/s, 0.0280 deg/s, as with one start, and 1 second start (its first
  // frames' guess knows no velocity yet), none kept; with the floors alone (5 mm, 0.75 deg, no
  // sigmas) and the plain margin (ties kept) 0.00929, 0.0332; with the floors alone and the 1.1x
  // margin the same figures, at 24 second starts.
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.00145);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.0280);
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.05 * runs[1].rpe.trans.rmse);
  EXPECT_EQ(runs[0].second_starts_kept, 0);
  EXPECT_LE(runs[0].second_starts, 3);
}

// A real Kinect's depth errs in blobs of neighbouring pixels (scripts/depth_noise: as a 3-px
// correlation length). Averaging over many pixels does not undo such errors, so a method whose
// precision came from per-pixel noise would lose it; acvo's must not. The room without texture,
// where the depth carries most: the same frames with the noise per pixel and in blobs. The dense
// depth term averages windows of pixels: it gains on the first and stays off on the second.
TEST(Sequences, DepthNoiseInBlobsAsARealKinectsCostsLittle) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.texture = false;
  const synth::SynthSequence per_pixel(o);
  o.depth_noise_correlation = 3.0;
  const synth::SynthSequence blobs(o);
  const Trajectory gt = groundtruthOf(per_pixel);
  ASSERT_EQ(gt.back().pose.matrix(), groundtruthOf(blobs).back().pose.matrix());
  Params sparse;
  sparse.coarse_to_fine.dense_point_to_plane = false;
  const auto a = runPolicies<2>({Params(), sparse}, per_pixel.size(),
                                [&](int i) { return per_pixel.frame(i).toFrame(); }, gt);
  const auto b = runPolicies<2>({Params(), sparse}, blobs.size(),
                                [&](int i) { return blobs.frame(i).toFrame(); }, gt);
  std::printf("  noise per pixel: RPE %.5f m/s %.4f deg/s (without the dense term %.5f, %.4f); "
              "in blobs: %.5f m/s %.4f deg/s (%.5f, %.4f)\n",
              a[0].rpe.trans.rmse, a[0].rpe.rot_deg.rmse, a[1].rpe.trans.rmse,
              a[1].rpe.rot_deg.rmse, b[0].rpe.trans.rmse, b[0].rpe.rot_deg.rmse,
              b[1].rpe.trans.rmse, b[1].rpe.rot_deg.rmse);
  for (int p = 0; p < 2; ++p) {
    EXPECT_EQ(a[p].lost, 0);
    EXPECT_EQ(b[p].lost, 0);
  }
  // Measured: per pixel 0.00080 m/s, 0.0174 deg/s (without the dense term 0.00156, 0.0258); in
  // blobs 0.00158, 0.0282 either way (ICPOdometry loses its precision there: docs/accuracy.md,
  // tenth round).
  EXPECT_LT(b[0].rpe.trans.rmse, 1.3 * 0.00158);
  EXPECT_LT(b[0].rpe.rot_deg.rmse, 1.3 * 0.0282);
  EXPECT_LT(a[0].rpe.trans.rmse, 1.3 * 0.00080);
  EXPECT_LT(a[0].rpe.rot_deg.rmse, 1.3 * 0.0174);
  // Blobs cost the selected points little against noise per pixel.
  EXPECT_LT(b[0].rpe.trans.rmse, 1.3 * a[1].rpe.trans.rmse);
  EXPECT_LT(b[0].rpe.rot_deg.rmse, 1.3 * a[1].rpe.rot_deg.rmse);
  // The dense term is off in blobs (the same figures to the last digit), and on per pixel halves
  // the error.
  EXPECT_EQ(b[0].rpe.trans.rmse, b[1].rpe.trans.rmse);
  EXPECT_LT(a[0].rpe.trans.rmse, 0.6 * a[1].rpe.trans.rmse);
  EXPECT_LT(a[0].rpe.rot_deg.rmse, 0.75 * a[1].rpe.rot_deg.rmse);
}

// Colour from a second camera, as 7-Scenes' (a Kinect's raw depth paired with its colour): 0.897
// times the depth camera's focal length, 2.5 cm beside it, the depth's noise in blobs. Once the
// colour check judges it unregistered (the tenth frame), each frame's colour is resampled to
// the depth camera by the focal ratio it found, and the photometric term is left out (the
// baseline's offset remains); as it came, the points chosen at the colour's edges sit where the
// texture appears, which slides along the surfaces with the motion. With
// resample_colour_baseline the colour is resampled by the camera the check found (its ratio and
// baseline).
TEST(Sequences, ColourFromASecondCameraIsResampledToTheDepthCamera) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.seed = 31;
  o.speed = 0.5;
  o.colour_focal_ratio = 0.897;
  o.colour_baseline = 0.025;
  o.depth_noise_correlation = 3.0;
  const synth::SynthSequence seq(o);
  Params as_it_came, with_baseline;
  as_it_came.odometry.resample_unregistered_colour = false;
  with_baseline.odometry.resample_colour_baseline = true;
  const auto runs = runPolicies<3>(
      {Params(), as_it_came, with_baseline}, seq.size(),
      [&](int i) { return seq.frame(i).toFrame(); }, groundtruthOf(seq));
  std::printf("  colour resampled: RPE %.5f m/s %.4f deg/s; as it came: %.5f m/s %.4f deg/s; "
              "with the baseline: %.5f m/s %.4f deg/s\n",
              runs[0].rpe.trans.rmse, runs[0].rpe.rot_deg.rmse, runs[1].rpe.trans.rmse,
              runs[1].rpe.rot_deg.rmse, runs[2].rpe.trans.rmse, runs[2].rpe.rot_deg.rmse);
  for (const auto& run : runs) EXPECT_EQ(run.lost, 0);
  // Measured 0.00619 m/s, 0.2339 deg/s resampled, 0.02319, 0.5195 as it came, 0.00524, 0.2346
  // with the baseline (150 frames, acvo_compare: 0.0069 / 0.211, 0.0232 / 0.528, 0.0061 /
  // 0.203; with the colour registered before the first frame, 0.0047 / 0.036: most of the
  // rotation error is the first ten frames').
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.00619);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.2339);
  EXPECT_GT(runs[1].rpe.trans.rmse, 3.0 * runs[0].rpe.trans.rmse);
  EXPECT_GT(runs[1].rpe.rot_deg.rmse, 1.8 * runs[0].rpe.rot_deg.rmse);
  EXPECT_LT(runs[2].rpe.trans.rmse, 1.3 * 0.00524);
  EXPECT_LT(runs[2].rpe.rot_deg.rmse, 0.281);  // 1.2x the measured
  EXPECT_LT(runs[2].rpe.trans.rmse, 0.95 * runs[0].rpe.trans.rmse);  // measured 0.85
}

// A lens's vignetting: the colour darkens by exp(-1 rho) towards the corners (43% at a corner),
// so a point's grey value changes as it crosses the image. The photometric term measures it per
// registration (CoarseToFineParams::photometric_vignetting); without it the residuals carry
// the falloff as if it were motion.
TEST(Sequences, VignettingIsMeasuredNotMistakenForMotion) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.vignetting = -1.0;
  const synth::SynthSequence seq(o);
  Params without = colourModelBase();
  without.coarse_to_fine.photometric_vignetting = false;
  // Measured (the dense term off: colourModelBase) 0.00047 m/s, 0.0090 deg/s measured and
  // 0.00097, 0.0185 not modelled.
  expectTheModelHelps(seq, groundtruthOf(seq), colourModelBase(), without, "vignetting measured",
                      "vignetting not modelled", {0.00047, 0.0090}, 1.5);
}

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
