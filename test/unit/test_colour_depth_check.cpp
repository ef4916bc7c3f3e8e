// ColourDepthCheck: where depth edges are found, which colour focal length fits them, and the
// verdicts on rendered sequences whose colour camera is known (registered, or 0.897 and 1.1
// times the depth's focal length), on frames with nothing to judge, and on the real sets (TUM:
// registered; 7-Scenes: its colour camera's 525 px against the depth's 585).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

#include "acvo/cloud/colour_depth_check.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/dataset/tum.hpp"
#include "synth/sequence.hpp"
#include "test_support.hpp"

namespace acvo {
namespace {

using State = ColourDepthCheck::State;

// Every kFrameStep-th frame of a rendered sequence (as Odometry looks), until
// decided.
ColourDepthCheck::Verdict judge(synth::SequenceOptions o,
                                const ColourDepthCheck::Options& options = {}) {
  const synth::SynthSequence sequence(o);
  ColourDepthCheck check(options);
  for (int i = 0; i < sequence.size() && !check.decided(); i += ColourDepthCheck::kFrameStep) {
    check.add(sequence.frame(i).toFrame());
  }
  return check.verdict();
}

synth::SequenceOptions exactRoom(double colour_focal_ratio, double colour_baseline = 0.0) {
  synth::SequenceOptions o;
  o.frames = 60;
  o.noise = false;
  o.colour_focal_ratio = colour_focal_ratio;
  o.colour_baseline = colour_baseline;
  return o;
}

// A step in depth (1 m on the left, 2 m from column 50 on) with the two columns at the step
// left without depth, as a Kinect leaves them: the edge is the near side's last column (3 px
// from the far side), nothing on the far side or in the flat parts; without the hole, the near
// side's last three columns.
TEST(ColourDepthCheck, DepthEdgesAreTheNearSideOfAJump) {
  cv::Mat depth(40, 100, CV_32FC1, cv::Scalar(1.0f));
  depth.colRange(50, 100).setTo(2.0f);
  depth.colRange(48, 50).setTo(0.0f);
  const auto edges = ColourDepthCheck::depthEdges(depth, 0.05);
  std::set<int> columns;
  for (const auto& [u, v] : edges) {
    columns.insert(u);
    EXPECT_GE(v, 3);
    EXPECT_LT(v, 37);
  }
  EXPECT_EQ(columns, (std::set<int>{47}));
  EXPECT_EQ(edges.size(), 34u);
  depth.colRange(48, 50).setTo(1.0f);
  columns.clear();
  for (const auto& [u, v] : ColourDepthCheck::depthEdges(depth, 0.05)) columns.insert(u);
  EXPECT_EQ(columns, (std::set<int>{47, 48, 49}));
  // Below the threshold (a 4% step) there is no edge.
  depth.colRange(50, 100).setTo(1.04f);
  EXPECT_TRUE(ColourDepthCheck::depthEdges(depth, 0.05).empty());
}

// A colour edge at column 320 + 0.9 (u - 320) of a depth edge at u = 420: the score peaks at 0.9.
TEST(ColourDepthCheck, TheScorePeaksWhereTheColourEdgeLies) {
  Camera camera;
  camera.cx = 320.0;
  camera.cy = 240.0;
  cv::Mat grey(480, 640, CV_8UC1, cv::Scalar(40));
  grey.colRange(410, 640).setTo(200);  // a colour edge between columns 409 and 410
  std::vector<std::array<int, 2>> edges;
  for (int v = 100; v < 380; ++v) edges.push_back({420, v});  // 320 + (410 - 320) / 0.9
  const auto s = ColourDepthCheck::scores(grey, camera, edges);
  const int best = int(std::max_element(s.begin(), s.end()) - s.begin());
  EXPECT_NEAR(ColourDepthCheck::ratioAt(best), 0.9, 0.011);
  EXPECT_GT(s[std::size_t(best)], 10.0 * s[ColourDepthCheck::kRatios / 2]);
}

TEST(ColourDepthCheck, ARegisteredRenderedRoomIsRegistered) {
  const auto v = judge(exactRoom(1.0));
  EXPECT_EQ(v.state, State::kRegistered) << v.best_ratio << " " << v.gain;
  EXPECT_NEAR(v.best_ratio, 1.0, 0.015);
  EXPECT_EQ(v.frames, 10);
}

// The camera of 0.897 is clear from its third frame on (gain 1.69, 1.58 in the quarters, every
// frame's best camera agreeing): the early verdict. The one of 1.1 stays under early_gain (1.42
// at three frames) and is found at the tenth (1.34).
TEST(ColourDepthCheck, AnUnregisteredColourCameraIsFoundWithItsFocalLength) {
  for (const auto& [ratio, frames] : {std::pair{0.897, 3}, std::pair{1.1, 10}}) {
    const auto v = judge(exactRoom(ratio));
    EXPECT_EQ(v.state, State::kUnregistered)
        << ratio << ": best " << v.best_ratio << " gain " << v.gain << " agreement " << v.agreement;
    EXPECT_NEAR(v.best_ratio, ratio, 0.025) << ratio;
    EXPECT_GT(v.gain, 1.2) << ratio;
    EXPECT_EQ(v.frames, frames) << ratio;
  }
  // Without the early rule, the clear camera too waits for the tenth frame.
  ColourDepthCheck::Options late;
  late.early_frames = late.frames_needed;
  const auto v = judge(exactRoom(0.897), late);
  EXPECT_EQ(v.state, State::kUnregistered);
  EXPECT_EQ(v.frames, 10);
}

// A room (seed 54) whose texture beside the silhouettes makes the score climb across the whole
// grid, from 0.58 of ratio 1's at 0.89 to 1.2x at 1.20, with no peak at its camera's 0.897:
// taken for a camera of ratio 1.20, its colour resampled by that cost acvo 3x in translation
// (0.0253 -> 0.0804 m/s). A best ratio at the grid's ends (kGridEnd) is no camera found; the
// grid of cameras with their centres climbs there too (1.19, 1 cm).
TEST(ColourDepthCheck, AScoreClimbingToTheGridsEndIsNoCamera) {
  synth::SequenceOptions o = exactRoom(0.897, 0.025);
  o.seed = 54;
  ColourDepthCheck check;
  const synth::SynthSequence sequence(o);
  for (int i = 0; i < sequence.size() && !check.decided(); ++i) {
    check.add(sequence.frame(i).toFrame());
  }
  const auto& v = check.verdict();
  EXPECT_GE(v.best_ratio, ColourDepthCheck::ratioAt(ColourDepthCheck::kRatios - 4) - 1e-9);
  EXPECT_GT(v.gain, 1.15);  // measured 1.20: by gain and offset alone, "unregistered"
  EXPECT_EQ(v.state, State::kRegistered);
  EXPECT_NE(check.describe().find("no focal ratio stands out"), std::string::npos)
      << check.describe();
  EXPECT_TRUE(ColourDepthCheck::atGridEnd(0));
  EXPECT_TRUE(ColourDepthCheck::atGridEnd(3));  // 0.83
  EXPECT_TRUE(ColourDepthCheck::atGridEnd(ColourDepthCheck::kRatios - 4));  // 1.17
  EXPECT_FALSE(ColourDepthCheck::atGridEnd(5));  // 0.85, a rendered room's camera found
  EXPECT_FALSE(ColourDepthCheck::atGridEnd(31));  // 1.11, another
}

// Without centres to search (max_baseline 0, or a negative one read as 0) the grid is the focal
// ratio alone, and a colour camera with no baseline is still found by it.
TEST(ColourDepthCheck, AGridWithoutCentresIsTheRatioAlone) {
  for (const double max_baseline : {0.0, -1.0}) {
    ColourDepthCheck::Options options;
    options.max_baseline = max_baseline;
    const auto v = judge(exactRoom(0.897), options);
    EXPECT_EQ(v.state, State::kUnregistered) << max_baseline;
    EXPECT_NEAR(v.grid_ratio, 0.9, 0.015) << max_baseline;
    EXPECT_EQ(v.grid_baseline, 0.0) << max_baseline;
    EXPECT_GT(v.gain, 1.2) << max_baseline;
  }
}

// The verdict of Odometry's own check on a rendered sequence (the pairs as it registered them:
// depthAsRegistered), once decided.
ColourDepthCheck::Verdict judgeAsRegistered(const synth::SequenceOptions& o) {
  const synth::SynthSequence sequence(o);
  Odometry odometry;
  for (int i = 0; i < sequence.size() && !odometry.colourCheck().decided(); ++i) {
    odometry.process(sequence.frame(i).toFrame());
  }
  return odometry.colourCheck().verdict();
}

// A hand-held camera at 0.8 m/s whose colour is taken 10 ms after its depth (free-running
// streams): the raw pairs' colour edges lie off the depth edges by the motion, which the focal
// ratio alone takes for another colour camera (every third frame: best 1.04, 1.18x the score at
// 1). The odometry's own check, which sees the pairs as it registered them (the depth moved to
// the colour's time: depthAsRegistered), finds them registered, and so does the grid of colour
// cameras with their centres on the raw pairs (measured: its best camera 1.03, no baseline,
// 1.18x).
TEST(ColourDepthCheck, AFastCameraWithLateColourIsNotTakenForUnregistered) {
  synth::SequenceOptions o;
  o.frames = 60;
  o.seed = 21;
  o.speed = 0.8;
  o.colour_delay = 0.01;
  o.depth_noise_correlation = 3.0;
  const auto v = judgeAsRegistered(o);
  const synth::SynthSequence sequence(o);
  ColourDepthCheck raw;
  for (int i = 0; i < sequence.size() && !raw.decided(); i += 3) {
    raw.add(sequence.frame(i).toFrame());  // the raw pairs, every third frame
  }
  const auto v_raw = raw.verdict();
  std::printf("  as registered: %s, camera %.2f, %.3f m, gain %.3f; raw: %s, camera %.2f, %.3f m, "
              "gain %.3f\n",
              toString(v.state).c_str(), v.grid_ratio, v.grid_baseline, v.gain,
              toString(v_raw.state).c_str(), v_raw.grid_ratio, v_raw.grid_baseline, v_raw.gain);
  EXPECT_EQ(v.state, State::kRegistered);
  EXPECT_NEAR(v.best_ratio, 1.0, 0.015);
  EXPECT_EQ(v_raw.state, State::kRegistered);
}

// A colour camera of 0.9 times the depth's focal length, 2.5 cm beside it, on a camera at 1 m/s
// whose colour is blurred over half a frame: the blur spreads each silhouette's colour edge over
// about 12 px, and the focal ratio alone climbs to the grid's end (0.81, 1.09x the score at
// 1: taken as registered, acvo 0.0114 m/s against 0.0016 resampled). The camera, found with its
// centre, stands out (measured: 0.89, 3 cm, 1.20x; 1.21x in all quarters but one; every frame's
// own best camera within 0.03 of it).
TEST(ColourDepthCheck, AColourCameraIsFoundThroughMotionBlur) {
  synth::SequenceOptions o;
  o.frames = 40;
  o.seed = 306;
  o.speed = 1.0;
  o.blur = true;
  o.colour_focal_ratio = 0.9;
  o.colour_baseline = 0.025;
  const auto v = judgeAsRegistered(o);
  std::printf("  camera %.2f, %.3f m, gain %.3f, quarters %.3f, agreement %.2f; ratio alone %.2f\n",
              v.grid_ratio, v.grid_baseline, v.gain, v.quarter_gain, v.agreement, v.best_ratio);
  ASSERT_EQ(v.state, State::kUnregistered);
  EXPECT_NEAR(v.best_ratio, 0.9, 0.025);
  EXPECT_NEAR(v.grid_ratio, 0.9, 0.02);
  EXPECT_NEAR(v.grid_baseline, 0.025, 0.01);
}

// A person walking across a registered camera's view: the colour 10 ms late moves the person's
// colour off its silhouette by its own motion, which no colour camera explains in the whole
// image.
// - Walking at 0.5 m/s (p1), the best camera of the grid, 1.15 and 3 cm at 1.34x, passes the
//   ratio's, the gain's and the frames' conditions and fits one quarter of the image only (1.01x
//   in all quarters but one): the quarters tell it (and its focal ratio alone near it, 1.18, lies
//   at the grid's end).
// - At 1 m/s with the colour 10 ms late (p6), the best camera is 0.98 and -2 cm here (1.34x),
//   within 0.04 of ratio 1. From p6's folder as acvo_synth writes it (its images in PNG),
//   acvo_tum finds 0.96 and -3 cm (1.31x; 1.19x in all quarters but one), whose focal ratio alone
//   near it, 0.99, tells it.
TEST(ColourDepthCheck, APersonWalkingIsNoColourCamera) {
  synth::SequenceOptions slow;
  slow.frames = 90;
  slow.seed = 201;
  slow.speed = 0.3;
  slow.walker_speed = 0.5;
  synth::SequenceOptions late = slow;
  late.seed = 206;
  late.speed = 0.4;
  late.walker_speed = 1.0;
  late.colour_delay = 0.01;
  const ColourDepthCheck::Options options;
  for (const auto& o : {slow, late}) {
    const auto v = judgeAsRegistered(o);
    std::printf("  walker %.1f m/s: %s, camera %.2f, %.3f m, gain %.3f, quarters %.3f, agreement "
                "%.2f, ratio alone %.2f\n",
                o.walker_speed, toString(v.state).c_str(), v.grid_ratio, v.grid_baseline, v.gain,
                v.quarter_gain, v.agreement, v.best_ratio);
    EXPECT_EQ(v.state, State::kRegistered) << o.walker_speed;
    if (o.walker_speed < 1.0) {
      // Every condition of the verdict but the quarters'.
      EXPECT_FALSE(ColourDepthCheck::atGridEnd(
          int(std::lround((v.grid_ratio - ColourDepthCheck::ratioAt(0)) / 0.01))));
      EXPECT_GE(std::abs(v.grid_ratio - 1.0), options.min_offset - 1e-9);
      EXPECT_GE(std::abs(v.best_ratio - 1.0), options.min_offset - 1e-9);
      EXPECT_GE(v.gain, options.min_gain);
      EXPECT_GE(v.agreement, options.min_agreement);
      EXPECT_LT(v.quarter_gain, options.min_quarter_gain);
    }
  }
}

// The mean absolute difference of two colour images over the pixels with depth in `depth`.
double colourDifference(const cv::Mat& a, const cv::Mat& b, const cv::Mat& depth) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  const cv::Scalar mean = cv::mean(diff, depth > 0.0f);
  return (mean[0] + mean[1] + mean[2]) / 3.0;
}

// Rooms whose colour camera has 0.897 and 1.1 times the depth camera's focal length (no
// baseline): resampled by that ratio, the colour is the registered room's but for the
// interpolation; as it came, it is off by up to 33 px at the border. A ratio above 1 leaves the
// border without colour: its depth is cleared. Ratio 1 changes nothing.
TEST(ColourDepthCheck, ResamplingByTheFocalRatioRegistersTheColour) {
  const synth::SynthSequence registered(exactRoom(1.0));
  const Frame truth = registered.frame(5).toFrame();
  for (const double ratio : {0.897, 1.1}) {
    const Frame as_came = synth::SynthSequence(exactRoom(ratio)).frame(5).toFrame();
    const Frame resampled = withColourResampled(as_came, ratio);
    const double before = colourDifference(as_came.color, truth.color, truth.depth);
    const double after = colourDifference(resampled.color, truth.color, resampled.depth);
    std::printf("  ratio %.3f: mean colour difference %.2f as it came, %.2f resampled\n", ratio,
                before, after);
    // Measured 25.44 -> 1.53 (0.897), 23.93 -> 1.05 (1.1).
    EXPECT_LT(after, 2.0);
    EXPECT_GT(before, 15.0);
    // Cleared where the colour camera saw nothing (ratio 1.1: u < cx (1 - 1 / 1.1) = 29 px and
    // v < cy (1 - 1 / 1.1) = 22 px, and as far from the other borders), kept elsewhere.
    const cv::Rect seen(40, 30, 560, 420);
    EXPECT_EQ(cv::countNonZero(resampled.depth(seen) != as_came.depth(seen)), 0);
    if (ratio > 1.0) {
      EXPECT_EQ(cv::countNonZero(resampled.depth.col(20)), 0);
      EXPECT_EQ(cv::countNonZero(resampled.depth.row(465)), 0);
    } else {
      EXPECT_EQ(cv::countNonZero(resampled.depth != as_came.depth), 0);
    }
  }
  const Frame same = withColourResampled(truth, 1.0);
  EXPECT_EQ(same.color.data, truth.color.data);
  EXPECT_EQ(same.depth.data, truth.depth.data);
}

// Kinect-like noise leaves the rendered room's silhouettes without depth on both sides: too few
// edge pixels to judge, and no false alarm.
TEST(ColourDepthCheck, TooFewDepthEdgesDecideNothing) {
  synth::SequenceOptions noisy = exactRoom(1.0);
  noisy.noise = true;
  const auto v = judge(noisy);
  EXPECT_NE(v.state, State::kUnregistered);

  // One plane filling the view has no depth edge at all; a blank colour image no colour edge.
  synth::SequenceOptions plane = exactRoom(0.897);
  plane.structure = false;
  const auto p = judge(plane);
  EXPECT_EQ(p.state, State::kUndecided);
  EXPECT_EQ(p.frames, 0);
  EXPECT_EQ(p.frames_seen, 60 / ColourDepthCheck::kFrameStep);

  const synth::SynthSequence room(exactRoom(1.0));
  ColourDepthCheck blank;
  for (int i = 0; i < 30; ++i) {
    Frame f = room.frame(i).toFrame();
    f.color = cv::Mat(f.color.size(), CV_8UC3, cv::Scalar(90, 120, 150));
    blank.add(f);
  }
  EXPECT_EQ(blank.verdict().state, State::kUndecided);
  EXPECT_EQ(blank.verdict().frames, 0);
  EXPECT_NE(blank.describe().find("undecided: 0 of 30 frames"), std::string::npos)
      << blank.describe();
  // A frame that is not usable is not looked at.
  blank.add(Frame{});
  EXPECT_EQ(blank.verdict().frames_seen, 30);
}

ColourDepthCheck::Verdict judgeFolder(const std::filesystem::path& folder) {
  const TumDataset data(folder.string());
  ColourDepthCheck check;
  for (std::size_t i = 0; i < data.size() && !check.decided();
       i += ColourDepthCheck::kFrameStep) {
    check.add(data.loadFrame(i));
  }
  return check.verdict();
}

TEST(ColourDepthCheck, RealSetsTumRegistered7ScenesNot) {
  const auto data = test::sharedDataDir();
  if (data.empty()) GTEST_SKIP() << "shared data (../shared/data) is absent";
  // Measured: teddy200 best 1.01, its best camera 1.01 with no baseline, 1.03x at ten frames;
  // kitchen7s_dev best 0.89 from its first three frames (the colour camera's 525 px over the
  // depth's 585: 0.897), its best camera 0.91 and 3 cm, 2.1x: clear from the third frame on.
  const auto teddy = judgeFolder(data / "tum_fr3_teddy200");
  EXPECT_EQ(teddy.state, State::kRegistered);
  EXPECT_NEAR(teddy.best_ratio, 1.0, 0.015);
  const auto kitchen = judgeFolder(data / "kitchen7s_dev");
  EXPECT_EQ(kitchen.state, State::kUnregistered);
  EXPECT_NEAR(kitchen.best_ratio, 0.905, 0.02);
  EXPECT_GT(kitchen.gain, 1.4);
  EXPECT_EQ(kitchen.frames, 3);
  EXPECT_EQ(teddy.frames, 10);
}

}  // namespace
}  // namespace acvo
