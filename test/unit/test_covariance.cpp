// The reported covariance against truth: normalised squared errors of the per-frame motion
// (NEES, 6 degrees of freedom) on a synthetic sequence with Kinect-like noise.
#include <algorithm>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "acvo/odometry.hpp"
#include "acvo/se3.hpp"
#include "synth/sequence.hpp"

namespace acvo {
namespace {

// chi-square with 6 degrees of freedom, 95% quantile.
constexpr double kChi2Six95 = 12.5916;

// NEES of each registration: the motion from the frame's camera to its keyframe's (the
// previous frame's with the previous_frame reference) against the exact one, with the
// reported motion_covariance (odometry.hpp).
std::vector<double> neesOf(const synth::SequenceOptions& o, int* lost) {
  const synth::SynthSequence seq(o);
  Odometry odo;
  std::vector<double> nees;
  std::vector<Eigen::Isometry3d> estimate;
  for (int i = 0; i < seq.size(); ++i) {
    const OdometryResult r = odo.process(seq.frame(i).toFrame());
    estimate.push_back(r.pose);
    if (i == 0) continue;
    if (r.tracking == Tracking::kLost) {
      ++*lost;
      continue;
    }
    const int k = int(r.keyframe_index);
    const Eigen::Isometry3d truth = seq.poses()[k].inverse() * seq.poses()[i];
    const Eigen::Isometry3d registered = estimate[k].inverse() * r.pose;
    // registered = exp(e) * estimate, e in the keyframe camera's axes.
    const Vector6d e = logSE3(truth * registered.inverse());
    nees.push_back(e.dot(r.motion_covariance.ldlt().solve(e)));
  }
  return nees;
}

class Covariance : public ::testing::TestWithParam<bool> {};

TEST_P(Covariance, NormalisedErrorsAreConsistentWithTheReportedCovariance) {
  synth::SequenceOptions o;
  o.frames = 150;
  o.texture = GetParam();
  int lost = 0;
  std::vector<double> nees = neesOf(o, &lost);
  ASSERT_GT(nees.size(), 100u);
  const double inside =
      double(std::count_if(nees.begin(), nees.end(), [](double x) { return x < kChi2Six95; })) /
      double(nees.size());
  std::sort(nees.begin(), nees.end());
  std::printf(
      "  %zu frames, %d lost: %.1f%% inside the 95%% ellipsoid, median NEES %.4g, "
      "95th percentile %.4g (chi2_6: 5.35, 12.59)\n",
      nees.size(), lost, 100 * inside, nees[nees.size() / 2],
      nees[size_t(0.95 * double(nees.size()))]);
  EXPECT_GE(inside, 0.80);
  EXPECT_LE(inside, 0.99);
}

INSTANTIATE_TEST_SUITE_P(StructuredRoom, Covariance, ::testing::Values(true, false),
                         [](const auto& info) { return info.param ? "textured" : "flat_colours"; });

}  // namespace
}  // namespace acvo
