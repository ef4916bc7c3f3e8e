// RPE and ATE: the TUM tools' own figures, and hand-derived figures for simple motions.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "acvo/dataset/evaluation.hpp"
#include "acvo/dataset/tum.hpp"
#include "clock_fixtures.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using acvo::DeltaUnit;

constexpr double kDeg = 180.0 / M_PI;
// arccos near 1 resolves angles only to ~1e-8 rad in double precision: a zero rotation error
// can read as a few 1e-7 degrees.
constexpr double kZeroDeg = 1e-5;

acvo::Trajectory fixture(const std::string& name) {
  return acvo::readTrajectory((acvo::test::sourceDir() / "test/data/eval" / name).string());
}

// ---------------------------------------------------------------------------- statistics

TEST(ErrorStats, MatchNumpyDefinitions) {
  const acvo::ErrorStats even = acvo::errorStats({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(even.count, 4u);
  EXPECT_DOUBLE_EQ(even.mean, 2.5);
  EXPECT_DOUBLE_EQ(even.median, 2.5);  // mean of the two middle values
  EXPECT_DOUBLE_EQ(even.rmse, std::sqrt(30.0 / 4.0));
  EXPECT_DOUBLE_EQ(even.std, std::sqrt(1.25));  // population std
  EXPECT_DOUBLE_EQ(even.min, 1.0);
  EXPECT_DOUBLE_EQ(even.max, 4.0);
  const acvo::ErrorStats odd = acvo::errorStats({5.0, 1.0, 2.0});
  EXPECT_DOUBLE_EQ(odd.median, 2.0);
  const acvo::ErrorStats empty = acvo::errorStats({});
  EXPECT_EQ(empty.count, 0u);
  EXPECT_EQ(empty.rmse, 0.0);
}

TEST(DeltaUnit, SpellingsOfTheTumTool) {
  for (const char* text : {"s", "f", "m", "rad", "deg"}) {
    EXPECT_EQ(acvo::toString(acvo::deltaUnitFromString(text)), text);
  }
  EXPECT_THROW(acvo::deltaUnitFromString("sec"), std::invalid_argument);
}

// ---------------------------------------------------------------------------- TUM fixtures

// expected.txt: "## <name> rpe --fixed_delta --delta 1 --delta_unit <u>" or "## <name> ate"
// headings, each followed by "<label> <value> <unit>" lines as the TUM tools print them.
struct ExpectedSection {
  std::string name, kind, unit;
  std::map<std::string, double> values;
};

std::vector<ExpectedSection> readExpected(const fs::path& path) {
  std::ifstream in(path);
  std::vector<ExpectedSection> sections;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string first;
    if (!(fields >> first)) continue;
    if (first == "##") {
      ExpectedSection s;
      fields >> s.name >> s.kind;
      for (std::string word; fields >> word;) {
        if (word == "--delta_unit") fields >> s.unit;
      }
      sections.push_back(s);
    } else if (!sections.empty()) {
      double value = 0.0;
      fields >> value;
      sections.back().values[first] = value;
    }
  }
  return sections;
}

void expectStats(const ExpectedSection& s, const std::string& label, const acvo::ErrorStats& got) {
  const std::map<std::string, double> figures = {{"rmse", got.rmse},     {"mean", got.mean},
                                                 {"median", got.median}, {"std", got.std},
                                                 {"min", got.min},       {"max", got.max}};
  for (const auto& [name, value] : figures) {
    const std::string key = label + "." + name;
    ASSERT_EQ(s.values.count(key), 1u) << s.name << " " << s.kind << ": no " << key;
    EXPECT_NEAR(value, s.values.at(key), 1e-6)
        << s.name << " " << s.kind << " " << s.unit << " " << key;
  }
}

TEST(Evaluation, ReproducesTheTumToolsOnTheFixtures) {
  const fs::path data = acvo::test::sharedDataDir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent";
  const fs::path dir = data / "eval_fixtures";
  const auto sections = readExpected(dir / "expected.txt");
  ASSERT_EQ(sections.size(), 6u);
  for (const ExpectedSection& s : sections) {
    const auto gt = acvo::readTrajectory((dir / (s.name + "_gt.txt")).string());
    const auto est = acvo::readTrajectory((dir / (s.name + "_est.txt")).string());
    if (s.kind == "rpe") {
      const acvo::RpeResult r = acvo::computeRpe(gt, est, 1.0, acvo::deltaUnitFromString(s.unit));
      EXPECT_EQ(static_cast<double>(r.pairs), s.values.at("compared_pose_pairs")) << s.name;
      expectStats(s, "translational_error", r.trans);
      expectStats(s, "rotational_error", r.rot_deg);
    } else {
      ASSERT_EQ(s.kind, "ate");
      const acvo::AteResult a = acvo::computeAte(gt, est);
      EXPECT_EQ(static_cast<double>(a.pairs), s.values.at("compared_pose_pairs")) << s.name;
      expectStats(s, "absolute_translational_error", a.trans);
    }
  }
}

// ---------------------------------------------------------------------------- own fixtures
// Expected values are derived in test/data/eval/README.md.

TEST(Evaluation, IdenticalTrajectoriesHaveNoError) {
  const auto gt = fixture("arc_gt.txt");
  for (const DeltaUnit unit : {DeltaUnit::kSeconds, DeltaUnit::kFrames, DeltaUnit::kMeters}) {
    const acvo::RpeResult r = acvo::computeRpe(gt, gt, 1.0, unit);
    EXPECT_GT(r.pairs, 5u);
    EXPECT_NEAR(r.trans.max, 0.0, 1e-12);
    EXPECT_NEAR(r.rot_deg.max, 0.0, kZeroDeg);
  }
  const acvo::AteResult a = acvo::computeAte(gt, gt);
  EXPECT_EQ(a.pairs, 31u);
  EXPECT_NEAR(a.trans.max, 0.0, 1e-12);
  EXPECT_TRUE(a.alignment.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12));
}

TEST(Evaluation, AnotherWorldFrameChangesNothingAndAteFindsIt) {
  const auto gt = fixture("arc_gt.txt"), est = fixture("arc_offset.txt");
  const acvo::RpeResult r = acvo::computeRpe(gt, est);
  EXPECT_EQ(r.pairs, 20u);
  EXPECT_NEAR(r.trans.max, 0.0, 1e-8);
  EXPECT_NEAR(r.rot_deg.max, 0.0, kZeroDeg);

  const acvo::AteResult a = acvo::computeAte(gt, est);
  EXPECT_EQ(a.pairs, 31u);  // stamps 4 ms apart associate
  EXPECT_NEAR(a.trans.max, 0.0, 1e-8);
  // The estimate is T * G: the alignment is T^-1.
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitX()))
                   .matrix();
  t.translation() = Eigen::Vector3d(1.0, -2.0, 0.5);
  EXPECT_TRUE((a.alignment * t).matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-7))
      << (a.alignment * t).matrix();
}

TEST(Evaluation, SpeedErrorOnAnArcGivesTheChordDifference) {
  const auto gt = fixture("arc_gt.txt"), est = fixture("arc_drift.txt");
  // |a - b| = 2 (v' - v) / w sin(w d / 2) with v' - v = 0.05 m/s, w = 0.2 rad/s.
  const acvo::RpeResult per_second = acvo::computeRpe(gt, est, 1.0, DeltaUnit::kSeconds);
  EXPECT_EQ(per_second.pairs, 20u);
  EXPECT_NEAR(per_second.trans.min, 0.5 * std::sin(0.1), 1e-6);
  EXPECT_NEAR(per_second.trans.max, 0.5 * std::sin(0.1), 1e-6);
  EXPECT_NEAR(per_second.rot_deg.max, 0.0, kZeroDeg);
  const acvo::RpeResult per_frame = acvo::computeRpe(gt, est, 1.0, DeltaUnit::kFrames);
  EXPECT_EQ(per_frame.pairs, 29u);
  EXPECT_NEAR(per_frame.trans.rmse, 0.5 * std::sin(0.01), 1e-6);
}

TEST(Evaluation, SpeedErrorOnALineGivesKnownRpeAndAte) {
  const auto gt = fixture("line_gt.txt"), est = fixture("line_drift.txt");
  const acvo::RpeResult s = acvo::computeRpe(gt, est, 1.0, DeltaUnit::kSeconds);
  EXPECT_EQ(s.pairs, 20u);
  EXPECT_NEAR(s.trans.rmse, 0.05, 1e-6);
  EXPECT_NEAR(s.trans.std, 0.0, 1e-6);
  const acvo::RpeResult f = acvo::computeRpe(gt, est, 1.0, DeltaUnit::kFrames);
  EXPECT_EQ(f.pairs, 29u);
  EXPECT_NEAR(f.trans.mean, 0.005, 1e-6);
  // 1 m of estimated path is 18 steps of 0.055 m (0.99 m, nearer than 19 steps, 1.045 m).
  const acvo::RpeResult m = acvo::computeRpe(gt, est, 1.0, DeltaUnit::kMeters);
  EXPECT_EQ(m.pairs, 12u);
  EXPECT_NEAR(m.trans.median, 18 * 0.005, 1e-6);

  // Residuals 0.005 |k - 15| for k = 0..30 once the centroids coincide.
  const acvo::AteResult a = acvo::computeAte(gt, est);
  EXPECT_EQ(a.pairs, 31u);
  EXPECT_NEAR(a.trans.rmse, 0.005 * std::sqrt(80.0), 1e-6);
  EXPECT_NEAR(a.trans.mean, 0.005 * 240.0 / 31.0, 1e-6);
  EXPECT_NEAR(a.trans.median, 0.005 * 8, 1e-6);
  EXPECT_NEAR(a.trans.max, 0.005 * 15, 1e-6);
  EXPECT_NEAR(a.trans.min, 0.0, 1e-6);
}

TEST(Evaluation, AngularRateErrorGivesKnownRotationError) {
  const auto gt = fixture("spin_gt.txt"), est = fixture("spin_drift.txt");
  struct Case {
    double delta;
    DeltaUnit unit;
    std::size_t pairs;
    double rad;
  };
  // Yaw rate error 0.05 rad/s; estimate steps of 0.025 rad (1.4324 deg) every 0.1 s.
  const Case cases[] = {{1.0, DeltaUnit::kSeconds, 20, 0.05},
                        {1.0, DeltaUnit::kFrames, 29, 0.005},
                        {0.1, DeltaUnit::kRadians, 26, 0.02},
                        {10.0, DeltaUnit::kDegrees, 23, 0.035}};
  for (const Case& c : cases) {
    const acvo::RpeResult r = acvo::computeRpe(gt, est, c.delta, c.unit);
    EXPECT_EQ(r.pairs, c.pairs) << acvo::toString(c.unit);
    EXPECT_NEAR(r.rot_deg.min, c.rad * kDeg, 1e-6) << acvo::toString(c.unit);
    EXPECT_NEAR(r.rot_deg.max, c.rad * kDeg, 1e-6) << acvo::toString(c.unit);
    EXPECT_NEAR(r.trans.max, 0.0, 1e-8) << acvo::toString(c.unit);
  }
  EXPECT_NEAR(acvo::computeAte(gt, est).trans.max, 0.0, 1e-9);
}

// ---------------------------------------------------------------------------- input handling

TEST(Evaluation, OrderOfPosesAndShadowedDuplicatesDoNotMatter) {
  const auto gt = fixture("arc_gt.txt"), est = fixture("arc_drift.txt");
  const acvo::RpeResult reference = acvo::computeRpe(gt, est);
  const acvo::AteResult reference_ate = acvo::computeAte(gt, est);

  acvo::Trajectory shuffled = est;
  std::reverse(shuffled.begin(), shuffled.end());
  std::rotate(shuffled.begin(), shuffled.begin() + 7, shuffled.end());
  // A pose given before another with the same stamp is replaced by it, as in the TUM tools.
  acvo::StampedPose stale = est[5];
  stale.pose.translation().x() += 10.0;
  shuffled.insert(shuffled.begin(), stale);

  const acvo::RpeResult r = acvo::computeRpe(gt, shuffled);
  EXPECT_EQ(r.pairs, reference.pairs);
  EXPECT_DOUBLE_EQ(r.trans.rmse, reference.trans.rmse);
  const acvo::AteResult a = acvo::computeAte(gt, shuffled);
  EXPECT_EQ(a.pairs, reference_ate.pairs);
  EXPECT_NEAR(a.trans.rmse, reference_ate.trans.rmse, 1e-12);
  for (const auto& [g, e] : a.matches) EXPECT_NEAR(gt[g].stamp, shuffled[e].stamp, 1e-9);
}

TEST(Evaluation, AteAssociationLimit) {
  const auto gt = fixture("line_gt.txt");
  acvo::Trajectory late = fixture("line_drift.txt");
  for (acvo::StampedPose& p : late) p.stamp += 0.03;
  EXPECT_THROW(acvo::computeAte(gt, late), std::runtime_error);
  EXPECT_EQ(acvo::computeAte(gt, late, 0.05).pairs, 31u);
}

TEST(Evaluation, TooFewPairsThrow) {
  const auto gt = fixture("line_gt.txt");
  acvo::Trajectory far = fixture("line_drift.txt");
  for (acvo::StampedPose& p : far) p.stamp += 100.0;
  EXPECT_THROW(acvo::computeRpe(gt, far), std::runtime_error);
  EXPECT_THROW(acvo::computeAte(gt, far), std::runtime_error);
  EXPECT_THROW(acvo::computeRpe(gt, acvo::Trajectory(gt.begin(), gt.begin() + 1)),
               std::runtime_error);
}

// ---------------------------------------------------------------------------- clock offset

TEST(Evaluation, AnOffsetIsAddedToTheEstimatesStampsAsTheTumToolsAddIt) {
  // The estimate's stamps 13 ms behind the reference's for the same poses: looked up at
  // stamp + 0.013 it is the reference itself.
  const acvo::Trajectory gt = acvo::test::sampledCamera(100.0, 4.0, 0.0);
  acvo::Trajectory early = gt;
  for (acvo::StampedPose& p : early) p.stamp -= 0.013;
  const acvo::RpeResult at_offset =
      acvo::computeRpe(gt, early, 1.0, DeltaUnit::kSeconds, 0.013);
  EXPECT_LT(at_offset.trans.rmse, 1e-9);
  EXPECT_LT(at_offset.rot_deg.rmse, kZeroDeg);
  EXPECT_LT(acvo::computeAte(gt, early, 0.02, 0.013).trans.rmse, 1e-9);
  // At offset 0 each pose meets the reference's 10 ms later (the nearest): a turn's error.
  EXPECT_GT(acvo::computeRpe(gt, early).rot_deg.rmse, 0.1);
  EXPECT_GT(acvo::computeAte(gt, early).trans.rmse, 1e-4);
}

TEST(ClockOffset, FoundFromTheFrameToFrameTurns) {
  // A 100 Hz reference; frames at 30 Hz whose poses are those 12.3 ms after their stamps, each
  // turned by 0.05 deg of noise.
  const acvo::Trajectory gt = acvo::test::sampledCamera(100.0, 6.0, 0.0);
  const acvo::Trajectory frames = acvo::test::sampledCamera(30.0, 6.0, 0.0123, 0.05);
  const acvo::ClockOffset c = acvo::estimateClockOffset(gt, {frames});
  EXPECT_NEAR(c.offset, 0.0123, 2e-4);  // found within 0.03 ms
  EXPECT_GE(c.turns, 170u);
  ASSERT_EQ(c.turn_rms_deg.size(), 1u);
  ASSERT_EQ(c.turn_rms_at_zero_deg.size(), 1u);
  // What is left is the noise: two poses' 0.05 deg each.
  EXPECT_LT(c.turn_rms_deg[0], 0.1);
  EXPECT_GT(c.turn_rms_at_zero_deg[0], 2.0 * c.turn_rms_deg[0]);
  // Evaluated there, the 1-s windows lose most of their error.
  const double at_zero = acvo::computeRpe(gt, frames).rot_deg.rmse;
  const double there =
      acvo::computeRpe(gt, frames, 1.0, DeltaUnit::kSeconds, c.offset).rot_deg.rmse;
  EXPECT_LT(there, 0.5 * at_zero);
  // The other way round too.
  const acvo::Trajectory late = acvo::test::sampledCamera(30.0, 6.0, -0.021, 0.05);
  EXPECT_NEAR(acvo::estimateClockOffset(gt, {late}).offset, -0.021, 2e-4);
}

TEST(ClockOffset, AMethodThatLostItsWayDoesNotMoveIt) {
  // One estimate precise, one with 3 deg of noise per frame (a method that lost its way):
  // each curve counts relative to its own least value, so the lost one's flat curve adds
  // little.
  const acvo::Trajectory gt = acvo::test::sampledCamera(100.0, 6.0, 0.0);
  const acvo::Trajectory good = acvo::test::sampledCamera(30.0, 6.0, 0.008, 0.05, 1);
  const acvo::Trajectory lost = acvo::test::sampledCamera(30.0, 6.0, 0.008, 3.0, 2);
  const acvo::ClockOffset c = acvo::estimateClockOffset(gt, {good, lost});
  EXPECT_NEAR(c.offset, 0.008, 2e-4);  // within 0.002 ms
  ASSERT_EQ(c.turn_rms_deg.size(), 2u);
  EXPECT_GT(c.turn_rms_deg[1], 10.0 * c.turn_rms_deg[0]);
}

TEST(ClockOffset, WeightsGiveEachMethodOneVote) {
  // One method's estimate 8 ms off, another's three settings 16 ms off, all equally precise:
  // counted as four curves the offset leans to the three, (8 + 3 x 16) / 4 = 14 ms; weighted
  // 1/3 each they are one vote, (8 + 16) / 2 = 12 ms.
  const acvo::Trajectory gt = acvo::test::sampledCamera(100.0, 6.0, 0.0);
  std::vector<acvo::Trajectory> estimates{acvo::test::sampledCamera(30.0, 6.0, 0.008, 0.05, 1)};
  for (unsigned seed = 2; seed <= 4; ++seed) {
    estimates.push_back(acvo::test::sampledCamera(30.0, 6.0, 0.016, 0.05, seed));
  }
  EXPECT_NEAR(acvo::estimateClockOffset(gt, estimates).offset, 0.014, 1e-3);
  const std::vector<double> one_vote{1.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
  EXPECT_NEAR(acvo::estimateClockOffset(gt, estimates, one_vote).offset, 0.012, 1e-3);
  // One positive weight per estimate, or none.
  EXPECT_THROW(acvo::estimateClockOffset(gt, estimates, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(acvo::estimateClockOffset(gt, estimates, {1.0, 0.0, 1.0, 1.0}),
               std::invalid_argument);
}

TEST(ClockOffset, RefusedWhereItCannotShow) {
  const acvo::Trajectory gt = acvo::test::sampledCamera(100.0, 6.0, 0.0);
  const acvo::Trajectory frames = acvo::test::sampledCamera(30.0, 6.0, 0.01);
  // A reference of one pose per frame (7-Scenes', the synthetic sequences'): no clock of its own.
  const acvo::Trajectory per_frame = acvo::test::sampledCamera(30.0, 6.0, 0.0);
  EXPECT_NE(acvo::test::errorOf([&] { acvo::estimateClockOffset(per_frame, {frames}); })
                .find("twice as often"),
            std::string::npos);
  // The same reference with every 2nd frame kept (acvo_compare --stride 2): sampled twice as
  // often as the frames now, and still without a clock of its own.
  acvo::Trajectory every_2nd;
  for (std::size_t k = 0; k < per_frame.size(); k += 2) every_2nd.push_back(per_frame[k]);
  EXPECT_NE(acvo::test::errorOf([&] { acvo::estimateClockOffset(per_frame, {every_2nd}); })
                .find("the reference's own"),
            std::string::npos);
  // A still camera: every offset fits as well.
  acvo::Trajectory still_gt = gt, still = frames;
  for (acvo::StampedPose& p : still_gt) p.pose = Eigen::Isometry3d::Identity();
  for (acvo::StampedPose& p : still) p.pose = Eigen::Isometry3d::Identity();
  still[5].pose.linear() = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NE(acvo::test::errorOf([&] { acvo::estimateClockOffset(still_gt, {still}); })
                .find("turns too little"),
            std::string::npos);
  // Beyond the search: 80 ms late, searched within 50 ms.
  const acvo::Trajectory far = acvo::test::sampledCamera(30.0, 6.0, 0.08);
  EXPECT_NE(acvo::test::errorOf([&] { acvo::estimateClockOffset(gt, {far}); }).find("edge"),
            std::string::npos);
  // Too few frames.
  const acvo::Trajectory few(frames.begin(), frames.begin() + 8);
  EXPECT_NE(acvo::test::errorOf([&] { acvo::estimateClockOffset(gt, {few}); }).find("at least"),
            std::string::npos);
}

}  // namespace
