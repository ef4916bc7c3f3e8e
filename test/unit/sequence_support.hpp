// Helpers of the whole-sequence tests (test_sequences, test_real_sequences,
// test_camera_conditions, test_people, test_keyframe_drift): odometry run with several settings
// over the same frames, the ground truth of a rendered sequence, and the errors of a motion.
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "acvo/dataset/evaluation.hpp"
#include "acvo/odometry/odometry.hpp"
#include "synth/sequence.hpp"

namespace acvo::test {

struct PolicyRun {
  RpeResult rpe;
  int lost = 0;
  Trajectory estimate;             // one pose per frame given
  std::vector<Tracking> tracking;  // the engine's judgement of each frame
  // frames whose finest level ran again from the guess, or that ran the start from the rest of
  // the points (OdometryResult::second_start)
  int second_starts = 0;
  int second_starts_kept = 0;  // ... and kept that result
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
inline const char* const kRunNames[] = {"coarse_to_fine", "adaptive", "fixed_schedule"};

inline Trajectory groundtruthOf(const synth::SynthSequence& seq) {
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
inline void expectTheModelHelps(const synth::SynthSequence& seq, const Trajectory& gt,
                                const Params& with, const Params& without, const char* name,
                                const char* name_without, Figures measured, double factor) {
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
// noise drawn per pixel the dense term carries much of the motion on its own, and what a model
// of the colour gains is measured with the colour leading.
inline Params colourModelBase() {
  Params p;
  p.coarse_to_fine.dense_point_to_plane = false;
  return p;
}

inline bool allFinite(const Trajectory& t) {
  for (const auto& p : t) {
    if (!p.pose.matrix().allFinite()) return false;
  }
  return true;
}

// Error of the estimated motion from pose a to pose b against the true one: (m, deg).
inline std::pair<double, double> motionError(const Trajectory& gt, const Trajectory& est, int a,
                                             int b) {
  const Eigen::Isometry3d e =
      (est[a].pose.inverse() * est[b].pose) * (gt[a].pose.inverse() * gt[b].pose).inverse();
  return {e.translation().norm(), Eigen::AngleAxisd(e.rotation()).angle() * 180.0 / M_PI};
}

// The true motion from pose a to pose b: (m, deg).
inline std::pair<double, double> trueMotion(const Trajectory& gt, int a, int b) {
  const Eigen::Isometry3d m = gt[a].pose.inverse() * gt[b].pose;
  return {m.translation().norm(), Eigen::AngleAxisd(m.rotation()).angle() * 180.0 / M_PI};
}

// Frames [first, end) of a rendered sequence with the default settings and with one start
// (OdometryParams::second_start off), each printed; neither may lose a frame.
inline std::array<PolicyRun, 2> withAndWithoutSecondStart(const synth::SynthSequence& seq,
                                                          int first, int end) {
  const Trajectory all = groundtruthOf(seq);
  const Trajectory gt(all.begin() + first, all.begin() + end);
  Params one_start;
  one_start.odometry.second_start = false;
  auto runs = runPolicies<2>(
      {Params(), one_start}, int(gt.size()), [&](int i) { return seq.frame(first + i).toFrame(); },
      gt);
  for (int p = 0; p < 2; ++p) {
    std::printf("  %s: RPE %.3g m/s %.3g deg/s, %d lost, %d second starts (%d kept)\n",
                p == 0 ? "default" : "one start", runs[p].rpe.trans.rmse, runs[p].rpe.rot_deg.rmse,
                runs[p].lost, runs[p].second_starts, runs[p].second_starts_kept);
    EXPECT_EQ(runs[p].lost, 0);
  }
  return runs;
}

}  // namespace acvo::test
