// Numerical faults of the list that the solver and odometry tests do not inject
// themselves: clouds of identical points, NaN and Inf inside clouds (points, labels) and inside
// frames (depth, colour of any value, intrinsics). Whatever the input, the solver returns a
// status and a finite transform, the odometry a finite pose. (Clouds of 0, 1 and 2 points and a
// NaN guess: test_solver, Align.TooFewPointsAndNonFiniteInputGiveAStatusNotNaN.)
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "acvo/odometry/odometry.hpp"
#include "acvo/registration/engine.hpp"
#include "cloud_fixtures.hpp"
#include "synth/sequence.hpp"

namespace acvo {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

LabelledCloud identicalPoints(int n) {
  LabelledCloud c;
  Label l;
  l << 0.5f, 0.5f, 0.5f, 0.1f, -0.1f;
  for (int k = 0; k < n; ++k) {
    c.points.emplace_back(0.1f, -0.2f, 2.0f);
    c.labels.push_back(l);
  }
  return c;
}

SolverResult alignClouds(const LabelledCloud& fixed, const LabelledCloud& moving) {
  const auto engine = makeRegistrationEngine(Params());
  return engine->align(*engine->prepare(fixed, true), *engine->prepare(moving, false),
                       Eigen::Isometry3d::Identity());
}

TEST(NumericFaults, CloudsOfIdenticalPointsGiveAStatusAndAFiniteTransform) {
  for (int n : {1, 2, 50, 500}) {
    SCOPED_TRACE(std::to_string(n) + " identical points");
    const LabelledCloud same = identicalPoints(n);
    const LabelledCloud surface = test::randomCloud(500, 3);
    for (const auto& [fixed, moving] : {std::pair{&same, &same}, std::pair{&same, &surface},
                                        std::pair{&surface, &same}}) {
      const SolverResult r = alignClouds(*fixed, *moving);
      EXPECT_TRUE(r.transform.matrix().allFinite()) << toString(r.status);
      ASSERT_TRUE(r.coarse_to_fine);
      EXPECT_TRUE(std::isfinite(r.coarse_to_fine->brightness_gain)) << toString(r.status);
      EXPECT_TRUE(std::isfinite(r.coarse_to_fine->vignetting)) << toString(r.status);
      if (n < CoarseToFineParams().min_points) {
        EXPECT_EQ(r.status, SolverStatus::kTooFewPoints);
      }
    }
  }
}

TEST(NumericFaults, NaNAndInfInsideACloudNeverReachTheTransform) {
  for (const float bad : {kNaN, kInf, -kInf}) {
    for (int field = 0; field < 2; ++field) {  // a point coordinate, a label
      SCOPED_TRACE(std::string(field == 0 ? "point" : "label") + " = " + std::to_string(bad));
      LabelledCloud cloud = test::randomCloud(500, 4);
      for (std::size_t k = 0; k < cloud.size(); k += 50) {
        if (field == 0) cloud.points[k][k % 3] = bad;
        if (field == 1) cloud.labels[k][k % 5] = bad;
      }
      const LabelledCloud spoilt = cloud;
      const LabelledCloud good = test::randomCloud(500, 4);
      for (const auto& [fixed, moving] : {std::pair{&good, &spoilt}, std::pair{&spoilt, &good},
                                          std::pair{&spoilt, &spoilt}}) {
        const SolverResult r = alignClouds(*fixed, *moving);
        EXPECT_TRUE(r.transform.matrix().allFinite()) << toString(r.status);
      }
    }
  }
}

TEST(NumericFaults, NaNAndInfInAFrameGiveAFinitePoseOrABadFrame) {
  synth::SequenceOptions o;
  o.frames = 3;
  o.noise = false;
  const synth::SynthSequence seq(o);
  Odometry odo;
  ASSERT_EQ(odo.process(seq.frame(0).toFrame()).tracking, Tracking::kFirstFrame);

  // Depth with NaN, +Inf and -Inf scattered over an otherwise good frame: those pixels are
  // invalid, the rest tracks.
  Frame holes = seq.frame(1).toFrame();
  for (int v = 0; v < holes.depth.rows; v += 3) {
    for (int u = v % 7; u < holes.depth.cols; u += 7) {
      holes.depth.at<float>(v, u) = (u + v) % 3 == 0 ? kNaN : (u + v) % 3 == 1 ? kInf : -kInf;
    }
  }
  OdometryResult r = odo.process(holes);
  EXPECT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard)
      << toString(r.tracking) << ": " << r.message;
  EXPECT_TRUE(r.pose.matrix().allFinite());
  EXPECT_TRUE(r.motion_covariance.allFinite());

  // Depth +Inf everywhere: nothing in range, lost, pose finite.
  Frame inf = seq.frame(2).toFrame();
  inf.depth.setTo(kInf);
  r = odo.process(inf);
  EXPECT_EQ(r.tracking, Tracking::kLost);
  EXPECT_NE(r.message.find("no valid depth"), std::string::npos) << r.message;
  EXPECT_TRUE(r.pose.matrix().allFinite());

  // Non-finite intrinsics: a bad frame, the state unchanged.
  for (const double bad : {double(kNaN), double(kInf)}) {
    Frame f = seq.frame(2).toFrame();
    f.camera.fx = bad;
    r = odo.process(f);
    EXPECT_EQ(r.tracking, Tracking::kBadFrame);
    EXPECT_TRUE(r.pose.matrix().allFinite());
    f = seq.frame(2).toFrame();
    f.camera.cx = bad;
    r = odo.process(f);
    EXPECT_EQ(r.tracking, Tracking::kBadFrame);
    EXPECT_NE(r.message.find("intrinsics"), std::string::npos) << r.message;
  }
  // A non-finite depth stamp: a bad frame naming it (it once moved the depth by a NaN delay
  // and came out lost, "no valid depth").
  for (const double bad : {double(kNaN), double(kInf)}) {
    Frame f = seq.frame(2).toFrame();
    f.depth_stamp = bad;
    r = odo.process(f);
    EXPECT_EQ(r.tracking, Tracking::kBadFrame) << r.message;
    EXPECT_NE(r.message.find("depth_stamp is not finite"), std::string::npos) << r.message;
  }
  EXPECT_TRUE(odo.pose().matrix().allFinite());
}

}  // namespace
}  // namespace acvo
