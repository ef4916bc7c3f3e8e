// VelocityFilter: the velocity over a colour/depth delay from the last frame's motion and the
// frame's own coarse one (docs/method.md §7), on simulated velocities with known errors.
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "acvo/velocity_filter.hpp"

namespace acvo {
namespace {

TEST(VelocityFilter, WeighsAlikeWhatNothingWasSeenOf) {
  VelocityFilter f;
  const Vector6d predicted = Vector6d::Zero(), measured = Vector6d::Constant(1.0);
  EXPECT_TRUE(VelocityFilter::blend(f.gain(), predicted, measured)
                  .isApprox(Vector6d::Constant(0.5), 1e-12));
  // The prediction wrong by 1e-3 along rotation about x, the measurement by 1 there: along x
  // the prediction; in the directions no sample has seen, half of each.
  Vector6d along_x = Vector6d::Zero();
  along_x[0] = 1.0;
  f.addChange(1e-3 * along_x);
  f.addCorrection(along_x);
  // A non-finite sample (a frame whose motion was not finite) is not one.
  f.addChange(Vector6d::Constant(std::numeric_limits<double>::quiet_NaN()));
  ASSERT_TRUE(f.gain().allFinite());
  const Vector6d blended = VelocityFilter::blend(f.gain(), predicted, measured);
  EXPECT_NEAR(blended[0], 1e-6 / (1e-6 + 1.0), 1e-9);
  for (int i = 1; i < 6; ++i) EXPECT_NEAR(blended[i], 0.5, 1e-9) << i;
  f.reset();
  EXPECT_TRUE(f.gain().isApprox(0.5 * Matrix6d::Identity(), 1e-12));
}

// A camera whose velocity changes by `change` (per part, rad/s and m/s) from frame to frame,
// measured by a registration wrong by `error`; `coupled`: that error lies along a rotation
// about y and a translation along x together (the ambiguity of a registration's coarse levels).
struct Errors {
  double predicted, measured, blended;
};
Errors simulate(double change, double error, bool coupled, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  VelocityFilter f;
  Vector6d truth = Vector6d::Zero();
  double se_p = 0, se_m = 0, se_b = 0;
  int count = 0;
  for (int k = 0; k < 3000; ++k) {
    Vector6d step, noise;
    for (int i = 0; i < 6; ++i) step[i] = change * n(rng);
    for (int i = 0; i < 6; ++i) noise[i] = (coupled ? 0.1 : 1.0) * error * n(rng);
    if (coupled) {
      const double along = error * n(rng);
      noise[1] += along;
      noise[3] += along;
    }
    const Vector6d predicted = truth;
    truth += step;
    const Vector6d measured = truth + noise;
    const Vector6d blended = VelocityFilter::blend(f.gain(), predicted, measured);
    if (k >= 100) {
      se_p += (predicted - truth).squaredNorm();
      se_m += (measured - truth).squaredNorm();
      se_b += (blended - truth).squaredNorm();
      ++count;
    }
    // What the odometry sees after the frame: its final velocity (here the truth) less the
    // last one, and less the coarse one.
    f.addChange(step);
    f.addCorrection(-noise);
  }
  return {std::sqrt(se_p / count), std::sqrt(se_m / count), std::sqrt(se_b / count)};
}

TEST(VelocityFilter, WeighsPredictionAndMeasurementByWhatEachMisses) {
  struct Case {
    const char* name;
    double change, error;
    bool coupled;
  };
  for (const Case c : {Case{"smooth camera", 0.01, 0.1, false},
                       Case{"hand-held camera", 0.1, 0.01, false},
                       Case{"both alike", 0.05, 0.05, false},
                       Case{"coupled error", 0.05, 0.05, true}}) {
    const Errors e = simulate(c.change, c.error, c.coupled, 7);
    std::printf("  %-16s predicted %.4f measured %.4f blended %.4f\n", c.name, e.predicted,
                e.measured, e.blended);
    // Never worse than the better of the two by more than the running averages' own noise
    // (measured: at most 1% above the better), and well below the better where they are
    // alike.
    EXPECT_LT(e.blended, 1.05 * std::min(e.predicted, e.measured)) << c.name;
  }
  // Measured: 0.77 of either where they are alike; 0.68 of the better where the measurement's
  // error has a direction (a gain per part, rotation and translation apart, cannot see it).
  const Errors alike = simulate(0.05, 0.05, false, 8);
  EXPECT_LT(alike.blended, 0.85 * std::min(alike.predicted, alike.measured));
  const Errors coupled = simulate(0.05, 0.05, true, 9);
  EXPECT_LT(coupled.blended, 0.75 * std::min(coupled.predicted, coupled.measured));
}

}  // namespace
}  // namespace acvo
