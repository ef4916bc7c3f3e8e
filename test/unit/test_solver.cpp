// The paper engine's formulas against independent computations (docs/method.md §3, §4), and
// the default engine's step extrapolation.
#include <gtest/gtest.h>

#include <iostream>

#include "acvo/registration/coarse_to_fine.hpp"
#include "acvo/registration/paper.hpp"
#include "acvo/math/se3.hpp"
#include "cloud_fixtures.hpp"

namespace acvo {
namespace {

// ---- step size -------------------------------------------------------------------------------
// 4E t^3 + 3D t^2 + 2C t + B with chosen roots r1, r2, r3: 4E (t-r1)(t-r2)(t-r3).
double stepFor(double r1, double r2, double r3, double E = 1.0) {
  const double a3 = 4 * E;
  const double a2 = -a3 * (r1 + r2 + r3), a1 = a3 * (r1 * r2 + r1 * r3 + r2 * r3),
               a0 = -a3 * r1 * r2 * r3;
  return solveStep(a0, a1 / 2, a2 / 3, E, 0.2, 100.0);
}

TEST(StepSize, SmallestPositiveRealRootOfKnownCubics) {
  EXPECT_NEAR(stepFor(0.3, 0.7, 2.0), 0.3, 1e-12);
  EXPECT_NEAR(stepFor(-1.0, 0.45, 5.0), 0.45, 1e-12);
  EXPECT_NEAR(stepFor(-1.0, -2.0, 0.05, -3.0), 0.05, 1e-12);
  EXPECT_NEAR(stepFor(1e-3, 1e-3, 7.0), 1e-3, 1e-6);  // double root
}

TEST(StepSize, DegenerateLeadingTermsAndNoRoot) {
  // E = 0: quadratic 3D t^2 + 2C t + B with roots 0.25 and 4 -> 0.25.
  EXPECT_NEAR(solveStep(1.0, -2.125, 1.0 / 3.0, 0.0, 0.2, 10.0), 0.25, 1e-12);
  // E = D = 0: linear 2C t + B = 0 -> t = 0.6.
  EXPECT_NEAR(solveStep(1.2, -1.0, 0.0, 0.0, 0.2, 10.0), 0.6, 1e-12);
  // Only negative / complex roots -> min_step.
  EXPECT_EQ(stepFor(-0.5, -1.0, -2.0), 0.2);
  EXPECT_EQ(solveStep(1.0, 1.0, 0.0, 0.0, 0.2, 10.0), 0.2);  // t = -0.5
  EXPECT_EQ(solveStep(0.0, 0.0, 0.0, 0.0, 0.2, 10.0), 0.2);
  // Cap honoured.
  EXPECT_EQ(solveStep(-3.0, 1.0, 0.0, 0.0, 0.2, 0.8), 0.8);  // root 1.5
}

TEST(FixedSchedule, LengthScalesOfTheOriginalCvo) {
  // The authors' code switches after iterations 3, 10 and 20.
  EXPECT_EQ(scheduledEll(0), 0.15);
  EXPECT_EQ(scheduledEll(3), 0.15);
  EXPECT_EQ(scheduledEll(4), 0.10);
  EXPECT_EQ(scheduledEll(10), 0.10);
  EXPECT_EQ(scheduledEll(11), 0.06);
  EXPECT_EQ(scheduledEll(20), 0.06);
  EXPECT_EQ(scheduledEll(21), 0.03);
  EXPECT_EQ(scheduledEll(500), 0.03);
}

// ---- objective derivatives ---------------------------------------------------------------------
struct Pair {
  LabelledCloud X, Z;
};

Pair offsetPair(unsigned seed, const Vector6d& motion_twist) {
  Pair p;
  p.X = test::randomCloud(600, seed, 0.3f);
  p.Z = test::transformed(p.X, expSE3(motion_twist).inverse());
  return p;
}

// A sparsification so small that no pair in these clouds is dropped: F is smooth.
PaperParams denseParams() {
  PaperParams p = paperParams().paper;
  p.sparsification = 1e-30;
  return p;
}

TEST(Gradient, MatchesFiniteDifferenceOfTheObjective) {
  const PaperParams p = denseParams();
  const Pair pr = offsetPair(11, (Vector6d() << 0.03, -0.02, 0.01, 0.03, 0.02, -0.01).finished());
  const auto fx = preparePaper(pr.X, p, true), mz = preparePaper(pr.Z, p, false);
  PaperKernel kernel(fx->cloud, mz->cloud, fx->grid, p);
  const double ell = 0.1;
  const CrossSums s = kernel.evaluate(Eigen::Isometry3d::Identity(), ell);
  // dF/dxi for y -> exp(xi^) y equals -(c/l^2) omega and -(d/l^2) v.
  Vector6d expected;
  expected << -p.omega_scale / (ell * ell) * s.omega, -p.v_scale / (ell * ell) * s.v;
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Vector6d e = Vector6d::Zero();
    e[k] = h;
    const double fp = test::bruteForce(pr.X, pr.Z, expSE3(e), ell, p).F;
    const double fm = test::bruteForce(pr.X, pr.Z, expSE3(-e), ell, p).F;
    const double fd = (fp - fm) / (2 * h);
    EXPECT_NEAR(expected[k], fd, 2e-4 * expected.norm()) << "component " << k;
  }
}

TEST(StepSums, BIsTheDerivativeAlongTheFlow) {
  const PaperParams p = denseParams();
  const Pair pr = offsetPair(12, (Vector6d() << -0.02, 0.03, 0.02, -0.02, 0.03, 0.02).finished());
  const auto fx = preparePaper(pr.X, p, true), mz = preparePaper(pr.Z, p, false);
  PaperKernel kernel(fx->cloud, mz->cloud, fx->grid, p);
  const double ell = 0.1;
  const CrossSums s = kernel.evaluate(Eigen::Isometry3d::Identity(), ell);
  const StepSums st = kernel.stepSums(s.omega, s.v);
  Vector6d xi;
  xi << s.omega, s.v;
  auto F = [&](double t) { return test::bruteForce(pr.X, pr.Z, expSE3(-t * xi), ell, p).F; };
  const double h = 1e-4;
  const double d1 = (F(h) - F(-h)) / (2 * h);
  EXPECT_NEAR(st.B, d1, 1e-5 * std::abs(d1));
  EXPECT_GT(st.B, 0.0) << "(omega, v) must be an ascent direction";
}

TEST(StepSums, CDEAreTheTaylorCoefficientsOfTheObjective) {
  const PaperParams p = denseParams();
  const Pair pr = offsetPair(14, (Vector6d() << 0.02, -0.03, 0.01, 0.03, 0.01, -0.02).finished());
  const auto fx = preparePaper(pr.X, p, true), mz = preparePaper(pr.Z, p, false);
  PaperKernel kernel(fx->cloud, mz->cloud, fx->grid, p);
  const double ell = 0.1;
  const CrossSums s = kernel.evaluate(Eigen::Isometry3d::Identity(), ell);
  const StepSums st = kernel.stepSums(s.omega, s.v);
  Vector6d xi;
  xi << s.omega, s.v;
  auto F = [&](double t) { return test::bruteForce(pr.X, pr.Z, expSE3(-t * xi), ell, p).F; };
  // Central differences on a scale where the quartic is well resolved.
  const double h = 0.004 / xi.norm();
  const double f0 = F(0), f1 = F(h), fm1 = F(-h), f2 = F(2 * h), fm2 = F(-2 * h);
  const double d2 = (-f2 + 16 * f1 - 30 * f0 + 16 * fm1 - fm2) / (12 * h * h);
  const double d3 = (f2 - 2 * f1 + 2 * fm1 - fm2) / (2 * h * h * h);
  const double d4 = (f2 - 4 * f1 + 6 * f0 - 4 * fm1 + fm2) / (h * h * h * h);
  EXPECT_NEAR(st.C, d2 / 2, 1e-3 * std::abs(d2 / 2));
  // D can be a near-cancellation of large terms: judge it on the scale of its neighbours C and E.
  EXPECT_NEAR(st.D, d3 / 6, 5e-3 * (std::abs(d3 / 6) + std::sqrt(std::abs(st.C * st.E))));
  EXPECT_NEAR(st.E, d4 / 24, 5e-3 * std::abs(d4 / 24));
}

TEST(LengthScale, GradientMatchesCentralDifferenceOfJ) {
  const PaperParams p = denseParams();
  const Pair pr = offsetPair(13, (Vector6d() << 0.01, 0.02, -0.01, 0.02, -0.01, 0.01).finished());
  const auto fx = preparePaper(pr.X, p, true), mz = preparePaper(pr.Z, p, false);
  PaperKernel kernel(fx->cloud, mz->cloud, fx->grid, p);
  auto J = [&](double ell) {
    const auto I = Eigen::Isometry3d::Identity();
    return test::bruteForce(pr.X, pr.X, I, ell, p).F + test::bruteForce(pr.Z, pr.Z, I, ell, p).F -
           2 * test::bruteForce(pr.X, pr.Z, I, ell, p).F;
  };
  for (double ell : {0.05, 0.1, 0.14}) {
    const CrossSums s = kernel.evaluate(Eigen::Isometry3d::Identity(), ell);
    const SelfSums xx = selfKernelSums(*fx, ell, p), yy = selfKernelSums(*mz, ell, p);
    const double analytic = (xx.sum_d2 + yy.sum_d2 - 2 * s.F_d2) / (ell * ell * ell);
    const double h = 1e-5;
    const double numeric = (J(ell + h) - J(ell - h)) / (2 * h);
    EXPECT_NEAR(analytic, numeric, 1e-4 * std::abs(numeric) + 1e-6) << "ell " << ell;
  }
}

// ---- whole registrations ------------------------------------------------------------------------
// Linear convergence taken at once: aligned steps shrinking by rho are extended by 1/(1-rho),
// rho capped; anything else is left as Gauss-Newton gave it.
TEST(Extrapolation, ExtendsShrinkingAlignedStepsOnly) {
  Vector6d previous;
  previous << 1e-3, -2e-3, 0.5e-3, 4e-3, 0.0, -1e-3;
  const Vector6d step = 0.4 * previous;
  EXPECT_TRUE(extrapolatedStep(step, previous, 0.5).isApprox(step / 0.6));
  EXPECT_TRUE(extrapolatedStep(0.8 * previous, previous, 0.5).isApprox(0.8 * previous / 0.5));
  EXPECT_EQ(extrapolatedStep(step, previous, 0.0), step);                      // off
  EXPECT_EQ(extrapolatedStep(-step, previous, 0.5), -step);                    // turned back
  EXPECT_EQ(extrapolatedStep(1.5 * previous, previous, 0.5), 1.5 * previous);  // growing
  EXPECT_EQ(extrapolatedStep(step, Vector6d::Zero(), 0.5), step);  // first step of a level
  Vector6d sideways = step;
  sideways[1] = -sideways[1];  // cosine with previous well below 0.9
  EXPECT_EQ(extrapolatedStep(sideways, previous, 0.5), sideways);
}

// The length-scale update of A-CVO: descent along dJ/dell, the bound shrinking on contact and
// never below ell_min; ascent with the authors' sign.
TEST(LengthScale, DescendsShrinksTheBoundOnContactAndStaysAboveTheMinimum) {
  PaperParams p = paperParams().paper;  // ell_min 0.0391, ell_max 0.15, step 0.3, factor 0.7
  p.ell_update = EllUpdate::kDescent;
  LengthScale ls{0.1, p.ell_max};
  EXPECT_FALSE(updateLengthScale(ls, 0.05, p));  // 0.1 - 0.3 * 0.05
  EXPECT_DOUBLE_EQ(ls.ell, 0.085);
  EXPECT_TRUE(updateLengthScale(ls, -1.0, p));  // to 0.385: the bound shrinks to 0.105
  EXPECT_DOUBLE_EQ(ls.ell_max, 0.15 * 0.7);
  EXPECT_DOUBLE_EQ(ls.ell, ls.ell_max);
  EXPECT_EQ(ls.reductions, 1);
  EXPECT_TRUE(updateLengthScale(ls, 10.0, p));  // far below: ell_min
  EXPECT_DOUBLE_EQ(ls.ell, p.ell_min);
  for (int k = 0; k < 20; ++k) updateLengthScale(ls, -1.0, p);
  EXPECT_DOUBLE_EQ(ls.ell_max, p.ell_min) << "the bound never drops below ell_min";
  LengthScale before = ls;
  EXPECT_FALSE(updateLengthScale(ls, std::nan(""), p));
  EXPECT_EQ(ls.ell, before.ell);
  p.ell_update = EllUpdate::kReference;
  LengthScale up{0.1, 0.15};
  updateLengthScale(up, 0.05, p);
  EXPECT_DOUBLE_EQ(up.ell, 0.115);
}

TEST(LengthScale, GradientIsNormalisedByThePairsThatEnterIt) {
  SelfSums xx, yy;
  CrossSums xy;
  xx.sum_d2 = 2.0, yy.sum_d2 = 3.0, xy.F_d2 = 1.0;
  // Every row counts in the normalisation, also rows left out of the sums (nnz_all).
  xx.nnz = xx.nnz_all = 10, yy.nnz = 7, yy.nnz_all = 12, xy.nnz = 4;
  EXPECT_DOUBLE_EQ(lengthScaleGradient(xx, yy, xy, 0.5), (2.0 + 3.0 - 2.0) / 0.125 / 14.0);
  xy.nnz = 20;  // descent: a non-positive count leaves the sum as it is
  EXPECT_DOUBLE_EQ(lengthScaleGradient(xx, yy, xy, 0.5), 3.0 / 0.125);
  // reference (the authors' code) divides by any non-zero count, negative included.
  EXPECT_DOUBLE_EQ(lengthScaleGradient(xx, yy, xy, 0.5, EllUpdate::kReference),
                   3.0 / 0.125 / -18.0);
  xy.nnz = 11;
  EXPECT_DOUBLE_EQ(lengthScaleGradient(xx, yy, xy, 0.5, EllUpdate::kReference), 3.0 / 0.125);
}

TEST(Align, IdenticalCloudsGiveIdentityInZeroIterations) {
  PaperParams p = paperParams().paper;
  const LabelledCloud X = test::randomCloud(1500, 21, 0.5f);
  const auto fx = preparePaper(X, p, true), mz = preparePaper(X, p, false);
  const CrossSums s =
      PaperKernel(fx->cloud, mz->cloud, fx->grid, p).evaluate(Eigen::Isometry3d::Identity(), 0.1);
  EXPECT_LT(s.omega.norm(), 1e-9);
  EXPECT_LT(s.v.norm(), 1e-9);
  for (EllPolicy policy : {EllPolicy::kAdaptive, EllPolicy::kFixedSchedule}) {
    p.ell_policy = policy;
    const SolverResult r = alignPaper(*fx, *mz, Eigen::Isometry3d::Identity(), p);
    EXPECT_EQ(r.status, SolverStatus::kConverged);
    EXPECT_EQ(r.iterations, 0);
    EXPECT_TRUE(r.transform.isApprox(Eigen::Isometry3d::Identity(), 1e-15));
    ASSERT_TRUE(r.paper);
    EXPECT_NEAR(r.paper->inner_product, 1.0, 1e-6);
  }
}

TEST(Align, RecoversSmallMotionsOfARandomSurfaceCloud) {
  const Vector6d motions[] = {
      (Vector6d() << 0, 0, 0, 0.03, -0.02, 0.02).finished(),             // pure translation
      (Vector6d() << 0.04, -0.03, 0.05, 0, 0, 0).finished(),             // pure rotation (~3.9 deg)
      (Vector6d() << 0.03, 0.02, -0.04, -0.03, 0.02, 0.025).finished(),  // both
  };
  for (EllPolicy policy : {EllPolicy::kAdaptive, EllPolicy::kFixedSchedule}) {
    PaperParams p = paperParams().paper;
    p.ell_policy = policy;
    p.max_iterations = 500;
    for (const auto& m : motions) {
      const Eigen::Isometry3d truth = expSE3(m);
      const LabelledCloud X = test::randomCloud(3000, 31, 0.6f);
      const LabelledCloud Z = test::transformed(X, truth.inverse());
      const auto fx = preparePaper(X, p, true), mz = preparePaper(Z, p, false);
      const SolverResult r = alignPaper(*fx, *mz, Eigen::Isometry3d::Identity(), p);
      const Vector6d err = logSE3(truth.inverse() * r.transform);
      EXPECT_LT(err.tail<3>().norm(), 1e-3)
          << "policy " << int(policy) << " iterations " << r.iterations;
      EXPECT_LT(err.head<3>().norm() * 180 / M_PI, 0.1) << "policy " << int(policy);
    }
  }
}

TEST(Align, LengthScaleStaysWithinBoundsAndEllMaxOnlyShrinks) {
  PaperParams p = paperParams().paper;
  p.max_iterations = 300;
  const LabelledCloud X = test::randomCloud(2000, 41, 0.6f);
  const LabelledCloud Z =
      test::transformed(X, expSE3((Vector6d() << 0.05, 0, 0.02, 0.05, 0.03, 0).finished()));
  const auto fx = preparePaper(X, p, true), mz = preparePaper(Z, p, false);
  for (EllUpdate update : {EllUpdate::kDescent, EllUpdate::kReference}) {
    p.ell_update = update;
    const SolverResult r = alignPaper(*fx, *mz, Eigen::Isometry3d::Identity(), p);
    ASSERT_FALSE(r.trace.empty());
    EXPECT_EQ(r.trace.front().ell, p.ell_init) << "ell starts from ell_init for every frame";
    double last_max = p.ell_max;
    for (const auto& it : r.trace) {
      EXPECT_GE(it.ell, p.ell_min);
      EXPECT_LE(it.ell, p.ell_max);
      EXPECT_LE(it.ell_max, last_max);
      last_max = it.ell_max;
    }
    EXPECT_GE(r.ell, p.ell_min);
    EXPECT_LE(r.ell, last_max);
    // A second registration starts again from the configured values.
    const SolverResult again = alignPaper(*fx, *mz, Eigen::Isometry3d::Identity(), p);
    EXPECT_EQ(again.trace.front().ell, p.ell_init);
    EXPECT_EQ(again.iterations, r.iterations) << "registration is deterministic";
  }
}

TEST(Align, TooFewPointsAndNonFiniteInputGiveAStatusNotNaN) {
  // Both engines, through the interface the odometry uses.
  for (Engine engine : {Engine::kPaper, Engine::kCoarseToFine}) {
    Params params = paperParams();
    params.registration.engine = engine;
    const auto e = makeRegistrationEngine(params);
    for (int n : {0, 1, 2}) {
      const auto c = e->prepare(test::randomCloud(n, 5), true);
      const SolverResult r = e->align(*c, *c, Eigen::Isometry3d::Identity());
      EXPECT_EQ(r.status, SolverStatus::kTooFewPoints) << toString(engine);
      EXPECT_TRUE(r.transform.matrix().allFinite());
    }
    const auto c = e->prepare(test::randomCloud(500, 5), true);
    Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
    bad.translation().x() = NAN;
    const SolverResult r = e->align(*c, *c, bad);
    EXPECT_EQ(r.status, SolverStatus::kNotFinite) << toString(engine);
    EXPECT_TRUE(r.transform.matrix().allFinite());
  }
}

}  // namespace
}  // namespace acvo
