// Whole sequences of the shared real Kinect frames (../shared/data: skipped where absent): the
// default engine and the paper's A-CVO and CVO on 7-Scenes' kitchen and TUM fr3/teddy, against
// their measured figures and the authors' code. Bounds are the figures measured here, with a
// margin.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "acvo/dataset/tum.hpp"
#include "sequence_support.hpp"
#include "test_support.hpp"

namespace acvo {
namespace {

using namespace acvo::test;  // the sequences' helpers (sequence_support.hpp)

// Each setting over a TUM folder's frames, from the ground-truth pose nearest its first frame
// (TUM's motion capture runs at 100 Hz, faster than the camera): each estimate at the frames'
// colour stamps, and its lost frames.
struct FolderRun {
  Trajectory estimate;
  int lost = 0;
};
template <std::size_t N>
std::array<FolderRun, N> runFolder(const TumDataset& data, const std::array<Params, N>& settings) {
  const Trajectory& gt = *data.groundtruth();
  const double t0 = data.frames().front().rgb.stamp;
  const auto nearest = std::min_element(gt.begin(), gt.end(), [t0](const auto& a, const auto& b) {
    return std::abs(a.stamp - t0) < std::abs(b.stamp - t0);
  });
  std::array<Odometry, N> odo;
  for (std::size_t k = 0; k < N; ++k) {
    odo[k] = Odometry(settings[k]);
    odo[k].reset(nearest->pose);
  }
  std::array<FolderRun, N> runs;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const Frame frame = data.loadFrame(i);
    const auto& e = data.frames()[i].rgb;
    for (std::size_t k = 0; k < N; ++k) {
      const OdometryResult r = odo[k].process(frame);
      runs[k].lost += r.tracking == Tracking::kLost;
      runs[k].estimate.push_back({e.stamp_text, e.stamp, r.pose});
    }
  }
  return runs;
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
  for (int p = 0; p < 3; ++p) {
    std::printf("  kitchen7s_dev %-14s RPE %.4f m/s %.3f deg/s, %d lost\n", kRunNames[p],
                runs[p].rpe.trans.rmse, runs[p].rpe.rot_deg.rmse, runs[p].lost);
  }
  // Measured 0.0112 m/s, 0.462 deg/s (default: its colour found unregistered at the third frame,
  // then resampled and the last level led by the depth, unregistered_colour resample_depth_led;
  // 0.0594, 2.477 with resample alone; with one keyframe and no window 0.0123, 0.557, and 0.0136,
  // 0.710 with the verdict at the tenth frame); paper.yaml 0.0628 m/s, 4.479 deg/s; cvo.yaml
  // 0.0893, 5.474. Bounds 1.1x.
  // 7-Scenes colour and depth come from two unregistered cameras.
  EXPECT_EQ(runs[0].lost, 0);
  EXPECT_LT(runs[0].rpe.trans.rmse, 0.0124);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 0.509);
  EXPECT_EQ(runs[1].lost, 0);
  EXPECT_LT(runs[1].rpe.trans.rmse, 0.07);
  EXPECT_LT(runs[1].rpe.rot_deg.rmse, 5.0);
  EXPECT_EQ(runs[2].lost, 0);
}

// TUM fr3/teddy (200 frames, hand-held, up to 100 deg/s) with motion-capture ground truth: the
// default engine within a margin of its measured figures, nothing lost, and well below the
// drift of the same engine registering frame to frame. (OpenCV's RgbdOdometry set up as its
// TUM sample, at 10 m, does better here: 0.0104 m/s, 0.496 deg/s; docs/accuracy.md's engines
// table.)
TEST(Sequences, RealHandHeldMotionIsTrackedWithoutLossOrDrift) {
  const auto shared = test::sharedDataDir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data not present";
  const TumDataset data((shared / "tum_fr3_teddy200").string());
  ASSERT_TRUE(data.groundtruth());
  const Trajectory& gt = *data.groundtruth();
  // The default (keyframes) and the same engine frame to frame, on the same frames.
  Params previous_frame;
  previous_frame.odometry.reference = Reference::kPreviousFrame;
  const auto runs = runFolder<2>(data, {Params(), previous_frame});
  const RpeResult rpe = computeRpe(gt, runs[0].estimate);
  const double ate = computeAte(gt, runs[0].estimate).trans.rmse;
  const double ate_previous = computeAte(gt, runs[1].estimate).trans.rmse;
  std::printf(
      "  tum_fr3_teddy200 default RPE %.4f m/s %.3f deg/s, ATE %.4f m (frame to frame "
      "%.4f m), %d lost\n",
      rpe.trans.rmse, rpe.rot_deg.rmse, ate, ate_previous, runs[0].lost);
  // Measured 0.0051 m/s, 0.455 deg/s; ATE 0.0052 m against 0.0146 m frame to frame (with one
  // keyframe and no window: 0.0057, 0.449, ATE 0.0060; the photometric term's forward direction
  // alone: 0.0059, 0.470, ATE 0.0061; the kernel alone: 0.0086, 0.579, ATE 0.0105; max_depth 4:
  // 0.0159, 1.066, ATE 0.0185). Bounds 1.3x.
  EXPECT_EQ(runs[0].lost, 0);
  EXPECT_LT(rpe.trans.rmse, 0.0067);
  EXPECT_LT(rpe.rot_deg.rmse, 0.592);
  // Keyframes against drift: at most 0.7 of the frame-to-frame ATE (the target).
  EXPECT_LT(ate, 0.7 * ate_previous);
  // The camera's stamps against the motion capture's clock: both modes' frame-to-frame turns
  // agree best with the reference's 12-13 ms before the stamps (RgbdOdometry's too;
  // docs/accuracy.md, "The reference's clock"), and there the 1-s windows lose an eighth of
  // their rotation error.
  const ClockOffset clock = estimateClockOffset(gt, {runs[0].estimate, runs[1].estimate});
  const RpeResult at_clock =
      computeRpe(gt, runs[0].estimate, 1.0, DeltaUnit::kSeconds, clock.offset);
  std::printf("  tum_fr3_teddy200 clock offset %.1f ms: RPE %.4f m/s %.3f deg/s\n",
              1e3 * clock.offset, at_clock.trans.rmse, at_clock.rot_deg.rmse);
  EXPECT_NEAR(clock.offset, -0.0127, 0.002);
  EXPECT_LT(at_clock.rot_deg.rmse, 0.9 * rpe.rot_deg.rmse);
}

// The paper's A-CVO (config/paper.yaml) and CVO (config/cvo.yaml) against the authors' public
// code, built and run on the same 193 teddy frames: A-CVO 0.0957 m/s, 5.78 deg/s; CVO 0.111 m/s,
// 6.45 deg/s. Each must be within 5% of those in both, nothing lost.
TEST(Sequences, PaperConfigsReproduceTheAuthorsCodeOnTeddy) {
  const auto shared = test::sharedDataDir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data not present";
  const TumDataset data((shared / "tum_fr3_teddy200").string());
  ASSERT_TRUE(data.groundtruth());
  const auto runs = runFolder<2>(data, {paperParams(), cvoParams()});
  const char* names[] = {"paper.yaml (A-CVO)", "cvo.yaml (CVO)"};
  const double authors[2][2] = {{0.0957, 5.78}, {0.111, 6.45}};
  for (int k = 0; k < 2; ++k) {
    const RpeResult rpe = computeRpe(*data.groundtruth(), runs[k].estimate);
    const double rt = rpe.trans.rmse / authors[k][0], rr = rpe.rot_deg.rmse / authors[k][1];
    std::printf(
        "  tum_fr3_teddy200 %-18s RPE %.4f m/s %.3f deg/s (%.3f / %.3f of the authors' "
        "code), %d lost\n",
        names[k], rpe.trans.rmse, rpe.rot_deg.rmse, rt, rr, runs[k].lost);
    // Measured: A-CVO 0.0959 / 5.971 (1.002 / 1.033); CVO 0.1094 / 6.305 (0.986 / 0.978).
    EXPECT_EQ(runs[k].lost, 0) << names[k];
    EXPECT_NEAR(rt, 1.0, 0.05) << names[k];
    EXPECT_NEAR(rr, 1.0, 0.05) << names[k];
  }
}

}  // namespace
}  // namespace acvo
