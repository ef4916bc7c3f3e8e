#include "acvo/solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <memory>
#include <optional>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "acvo/cross_kernel.hpp"
#include "acvo/se3.hpp"

namespace acvo {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Smallest positive root of a t + b = 0 / a t^2 + b t + c = 0 (none: +inf).
double smallestPositiveLinear(double a, double b) {
  if (a == 0.0) return INFINITY;
  const double t = -b / a;
  return t > 0.0 ? t : INFINITY;
}

double smallestPositiveQuadratic(double a, double b, double c) {
  const double scale = std::max({std::abs(a), std::abs(b), std::abs(c)});
  if (scale == 0.0) return INFINITY;
  if (std::abs(a) <= 1e-14 * scale) return smallestPositiveLinear(b, c);
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return INFINITY;
  // Numerically stable pair of roots.
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  double best = INFINITY;
  for (double t : {q / a, q != 0.0 ? c / q : INFINITY}) {
    if (t > 0.0 && std::isfinite(t)) best = std::min(best, t);
  }
  return best;
}

// Real roots of t^3 + a t^2 + b t + c (trigonometric / Cardano), polished by Newton steps.
double smallestPositiveCubic(double A3, double A2, double A1, double A0) {
  const double scale = std::max({std::abs(A3), std::abs(A2), std::abs(A1), std::abs(A0)});
  if (scale == 0.0) return INFINITY;
  if (std::abs(A3) <= 1e-14 * scale) return smallestPositiveQuadratic(A2, A1, A0);
  const double a = A2 / A3, b = A1 / A3, c = A0 / A3;
  const double Q = (a * a - 3.0 * b) / 9.0;
  const double R = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
  double roots[3];
  int count = 0;
  if (R * R < Q * Q * Q) {
    const double theta = std::acos(std::clamp(R / std::sqrt(Q * Q * Q), -1.0, 1.0));
    const double m = -2.0 * std::sqrt(Q);
    roots[0] = m * std::cos(theta / 3.0) - a / 3.0;
    roots[1] = m * std::cos((theta + 2.0 * M_PI) / 3.0) - a / 3.0;
    roots[2] = m * std::cos((theta - 2.0 * M_PI) / 3.0) - a / 3.0;
    count = 3;
  } else {
    const double Aa = -std::copysign(std::cbrt(std::abs(R) + std::sqrt(R * R - Q * Q * Q)), R);
    const double Bb = Aa != 0.0 ? Q / Aa : 0.0;
    roots[0] = Aa + Bb - a / 3.0;
    count = 1;
  }
  double best = INFINITY;
  for (int k = 0; k < count; ++k) {
    double t = roots[k];
    for (int it = 0; it < 3; ++it) {  // polish
      const double f = ((t + a) * t + b) * t + c;
      const double df = (3.0 * t + 2.0 * a) * t + b;
      if (df == 0.0) break;
      t -= f / df;
    }
    if (t > 0.0 && std::isfinite(t)) best = std::min(best, t);
  }
  return best;
}

}  // namespace

Vector6d conjugateDirection(const Vector6d& g, const Vector6d& g_prev, const Vector6d& d_prev) {
  const double g_prev2 = g_prev.squaredNorm();
  if (!(g_prev2 > 0.0)) return g;
  // Polak-Ribiere with the "+" restart: beta drops to 0 (plain gradient) when the gradient has
  // turned so far that the previous direction no longer helps, e.g. after the length-scale moved.
  const double beta = std::max(0.0, g.dot(g - g_prev) / g_prev2);
  const Vector6d d = g + beta * d_prev;
  // The line search only moves forward: a direction that does not ascend restarts from g.
  return d.dot(g) > 0.0 && d.allFinite() ? d : g;
}

namespace {

// The coarse result replaces the guess only when the main objective is this much larger there:
// near the optimum the coarse stage's bias (a subset, a blurred objective) would otherwise cost
// accuracy (measured: RPE 0.0104 against 0.0089 m/s on the textured synthetic room).
constexpr double kCoarseGain = 1.25;
// Steps this well aligned (cosine) are taken as one linear convergence (extrapolatedStep).
constexpr double kAlignedSteps = 0.9;

// A few CVO iterations at the wide fixed length-scale coarse_ell on an evenly strided subset of
// the moving points: cheap, and they bring motions of several degrees within reach of the main
// stage. Returns the improved transform (the input when nothing could be done).
Eigen::Isometry3d coarseAlign(const PreparedCloud& fixed, const PreparedCloud& moving,
                              Eigen::Isometry3d T, const SolverParams& p, int* iterations) {
  PreparedCloud subset;
  const int n = int(moving.size());
  const int stride = std::max(1, n / std::max(p.coarse_points, 1));
  for (int j = 0; j < n; j += stride) {
    subset.cloud.points.push_back(moving.cloud.points[j]);
    subset.cloud.labels.push_back(moving.cloud.labels[j]);
  }
  CrossKernel kernel(fixed, subset, p, &fixed.coarse_grid);
  for (int it = 0; it < p.coarse_iterations; ++it) {
    const CrossSums& s = kernel.evaluate(T, p.coarse_ell);
    if (!s.omega.allFinite() || !s.v.allFinite()) break;
    if (s.omega.norm() < p.eps_gradient && s.v.norm() < p.eps_gradient) break;
    const StepSums st = kernel.stepSums(s.omega, s.v);
    const double step = solveStep(st.B, st.C, st.D, st.E, p.min_step, p.max_step);
    Vector6d xi;
    xi << s.omega, s.v;
    const Eigen::Isometry3d dT = expSE3(-step * xi);
    if (!dT.matrix().allFinite()) break;
    T = normalized(dT * T);
    ++*iterations;
    // The coarse optimum is only a starting point: stop well before full convergence.
    if (step * xi.norm() < 10.0 * p.eps_transform) break;
  }
  return T;
}

// The start of the main stage: the coarse stage's result when the main stage's own objective
// (at its first length-scale) is kCoarseGain times higher there than at the guess, the guess
// otherwise (the coarse stage sees a subset and a blurred objective).
Eigen::Isometry3d coarseStart(CrossKernel& kernel, const PreparedCloud& fixed,
                              const PreparedCloud& moving, const Eigen::Isometry3d& guess,
                              const SolverParams& p, int* iterations) {
  const Eigen::Isometry3d coarse = coarseAlign(fixed, moving, guess, p, iterations);
  const double ell0 = p.ell_policy == EllPolicy::kAdaptive ? p.ell_init : scheduledEll(0);
  const double F_guess = kernel.evaluate(guess, ell0).F;
  return kernel.evaluate(coarse, ell0).F > kCoarseGain * F_guess ? coarse : guess;
}

// Every k-th point of a cloud (k = size / count, at least 1), labels with them.
PreparedCloud strided(const PreparedCloud& cloud, int count) {
  PreparedCloud subset;
  const int n = int(cloud.size());
  const int stride = std::max(1, n / std::max(count, 1));
  for (int j = 0; j < n; j += stride) {
    subset.cloud.points.push_back(cloud.cloud.points[j]);
    subset.cloud.labels.push_back(cloud.cloud.labels[j]);
  }
  return subset;
}

// One Gauss-Newton step on the minorising quadratic of the last evaluate() (CrossSums::gn_H):
// the left increment that raises F. Identity when the pairs constrain nothing.
Eigen::Isometry3d levelStep(const CrossSums& s) {
  const Eigen::LDLT<Matrix6d> ldlt(s.gn_H);
  if (ldlt.info() != Eigen::Success || !(s.gn_H.trace() > 0.0))
    return Eigen::Isometry3d::Identity();
  const Vector6d xi = ldlt.solve(s.gn_g);
  return xi.allFinite() ? expSE3(xi) : Eigen::Isometry3d::Identity();
}

}  // namespace

Vector6d extrapolatedStep(const Vector6d& step, const Vector6d& previous, double max_ratio) {
  const double n = step.norm(), n_prev = previous.norm();
  if (!(max_ratio > 0.0) || !(n > 0.0) || !(n_prev > 0.0)) return step;
  const double ratio = n / n_prev;
  if (!(ratio < 1.0) || step.dot(previous) < kAlignedSteps * n * n_prev) return step;
  return step / (1.0 - std::min(ratio, max_ratio));
}

namespace {

// coarse_to_fine (not in the paper): a Gaussian kernel with its tails kept (sparsification far
// below the paper's), maximised by Gauss-Newton steps at each length-scale of levelElls,
// from the widest (a subset of the moving points) to the narrowest (all of them).
void alignLevels(const PreparedCloud& fixed, const PreparedCloud& moving, Eigen::Isometry3d T,
                 const SolverParams& p, SolverResult& result) {
  const std::vector<double> ells = levelElls(p);
  const int levels = int(ells.size());
  std::optional<PreparedCloud> subset;
  std::unique_ptr<CrossKernel> kernel;
  result.status = SolverStatus::kConverged;
  for (int level = 0; level < levels; ++level) {
    const double ell = ells[level];
    const bool last = level + 1 == levels;
    // Pairs per point grow with the kernel's reach: fewer moving points at the wide levels
    // (level_points at the first, in proportion to 1 / ell after it, all at the last).
    const int count = int(std::min<double>(moving.size(), p.level_points * ells.front() / ell));
    const PreparedCloud* points = &moving;
    if (!last && count < int(moving.size())) {
      subset = strided(moving, count);
      points = &*subset;
    }
    const VoxelGrid* grid = last ? &fixed.grid : &fixed.level_grids[std::size_t(level)];
    kernel = std::make_unique<CrossKernel>(fixed, *points, p, grid);
    // A level need not resolve the motion finer than its length-scale allows: the next level
    // refines it (measured: a third fewer iterations, the same accuracy).
    const double eps = p.level_eps * ell / ells.back();
    Vector6d previous = Vector6d::Zero();
    for (int it = 0; it < p.level_iterations; ++it) {
      const auto t0 = Clock::now();
      const CrossSums& s = kernel->evaluate(T, ell);
      result.ms_neighbours += msSince(t0);
      const Eigen::Isometry3d gn_step = levelStep(s);
      if (!gn_step.matrix().allFinite()) {
        result.status = SolverStatus::kNotFinite;
        return;
      }
      const Vector6d xi = extrapolatedStep(logSE3(gn_step), previous, p.level_acceleration);
      T = normalized(expSE3(xi) * T);
      previous = xi;
      result.trace.push_back({ell, ell, 1.0, xi.norm(), s.F, s.nnz});
      ++result.iterations;
      if (xi.head<3>().norm() < eps && xi.tail<3>().norm() < eps) break;
      if (last && it + 1 == p.level_iterations) result.status = SolverStatus::kMaxIterations;
    }
    if (points != &moving) kernel.reset();
  }
  result.transform = T;
  // Final figures on the full cloud at the finest length-scale.
  if (!kernel) kernel = std::make_unique<CrossKernel>(fixed, moving, p, &fixed.grid);
  const CrossSums& s = kernel->evaluate(T, ells.back());
  result.ell = ells.back();
  result.nnz = std::size_t(s.nnz);
  result.matched_fraction = double(s.matched) / double(std::max<std::size_t>(moving.size(), 1));
  result.objective = s.F;
  const SelfSums xx = selfKernelSums(fixed, ells.back(), p);
  const SelfSums yy = selfKernelSums(moving, ells.back(), p);
  result.inner_product = xx.sum > 0 && yy.sum > 0 ? s.F / std::sqrt(xx.sum * yy.sum) : 0.0;
  // The information of the minorising quadratic at the optimum (the Gauss-Newton matrix the
  // steps solve with); the exact curvature of the narrow kernel is no better conditioned.
  result.hessian = -s.gn_H;
  result.list_builds = kernel->candidateListBuilds();
}

}  // namespace

std::string toString(SolverStatus s) {
  switch (s) {
    case SolverStatus::kConverged:
      return "converged";
    case SolverStatus::kMaxIterations:
      return "max_iterations";
    case SolverStatus::kTooFewPoints:
      return "too_few_points";
    case SolverStatus::kNotFinite:
      return "not_finite";
  }
  return "unknown";
}

double solveStep(double B, double C, double D, double E, double min_step, double max_step) {
  double t = smallestPositiveCubic(4.0 * E, 3.0 * D, 2.0 * C, B);
  if (!std::isfinite(t)) t = min_step;
  return std::min(t, max_step);
}

bool LengthScale::pinned(const SolverParams& p) const {
  return ell <= p.ell_min || ell >= ell_max;
}

double lengthScaleGradient(const SelfSums& xx, const SelfSums& yy, const CrossSums& xy,
                           double ell) {
  double grad = (xx.sum_d2 + yy.sum_d2 - 2.0 * xy.F_d2) / (ell * ell * ell);
  // Normalised by the pairs that entered it, as the authors' code does.
  const double denom = double(xx.nnz + yy.nnz - 2 * xy.nnz);
  if (denom > 0.0) grad /= denom;
  return grad;
}

bool updateLengthScale(LengthScale& ls, double gradient, const SolverParams& p) {
  if (!std::isfinite(gradient)) return false;
  ls.ell = p.ell_update == EllUpdate::kReference ? ls.ell + p.ell_step * gradient
                                                 : ls.ell - p.ell_step * gradient;
  if (ls.ell >= ls.ell_max) {
    // ell_max never drops below ell_min: past that the bound would shrink forever.
    ls.ell_max = std::max(ls.ell_max * p.ell_reduction, p.ell_min);
    ++ls.reductions;
    ls.ell = ls.ell_max;
  }
  ls.ell = std::max(ls.ell, p.ell_min);
  return ls.pinned(p);
}

bool StallTracker::stalls(double ell, double F, const Eigen::Isometry3d& T) {
  if (patience_ <= 0) return false;
  if (ell != ell_) {
    ell_ = ell;
    best_F_ = F;
    best_T_ = T;
    since_best_ = 0;
  } else if (F > best_F_) {
    best_F_ = F;
    best_T_ = T;
    since_best_ = 0;
  } else if (++since_best_ >= patience_) {
    return true;
  }
  return false;
}

Vector6d SearchState::next(const Vector6d& g, SearchDirection kind) {
  const bool first = !started_;
  started_ = true;
  Vector6d d = kind == SearchDirection::kConjugateGradient && !first
                   ? conjugateDirection(g, g_prev_, d_prev_)
                   : g;
  g_prev_ = g;
  d_prev_ = d;
  return d;
}

double scheduledEll(int iteration) {
  if (iteration < 2) return 0.15;
  if (iteration < 9) return 0.10;
  if (iteration < 19) return 0.06;
  return 0.03;
}

SolverResult align(const PreparedCloud& fixed, const PreparedCloud& moving,
                   const Eigen::Isometry3d& guess, const SolverParams& p) {
  const auto t_start = Clock::now();
  SolverResult result;
  result.transform = guess;
  result.ell = p.ell_policy == EllPolicy::kAdaptive ? p.ell_init : scheduledEll(0);
  if (int(fixed.size()) < p.min_points || int(moving.size()) < p.min_points) {
    result.status = SolverStatus::kTooFewPoints;
    result.ms_total = msSince(t_start);
    return result;
  }
  if (!fixed.reference) {
    throw std::logic_error("align: the fixed cloud is not prepared as a reference");
  }
  if (!guess.matrix().allFinite()) {
    result.status = SolverStatus::kNotFinite;
    result.transform = Eigen::Isometry3d::Identity();
    result.ms_total = msSince(t_start);
    return result;
  }

  if (p.ell_policy == EllPolicy::kCoarseToFine) {
    alignLevels(fixed, moving, guess, p, result);
    if (!result.transform.matrix().allFinite() || result.status == SolverStatus::kNotFinite) {
      result.status = SolverStatus::kNotFinite;
      result.transform = guess;
    }
    result.ms_total = msSince(t_start);
    return result;
  }

  CrossKernel kernel(fixed, moving, p);
  const bool adaptive = p.ell_policy == EllPolicy::kAdaptive;
  Eigen::Isometry3d T = guess;
  if (p.coarse_ell > 0.0 && p.coarse_iterations > 0 && !fixed.coarse_grid.empty()) {
    const auto t0 = Clock::now();
    T = coarseStart(kernel, fixed, moving, guess, p, &result.coarse_iterations);
    result.ms_neighbours += msSince(t0);
  }

  LengthScale ls{p.ell_init, p.ell_max};
  SearchState direction;
  StallTracker stall(p.stall_iterations);
  result.status = SolverStatus::kMaxIterations;
  int it = 0;
  for (; it < p.max_iterations; ++it) {
    const double used_ell = adaptive ? ls.ell : scheduledEll(it);
    auto t0 = Clock::now();
    const CrossSums& s = kernel.evaluate(T, used_ell);
    result.ms_neighbours += msSince(t0);
    if (!s.omega.allFinite() || !s.v.allFinite()) {
      result.status = SolverStatus::kNotFinite;
      break;
    }
    if (s.omega.norm() < p.eps_gradient && s.v.norm() < p.eps_gradient) {
      result.status = SolverStatus::kConverged;
      break;
    }
    // A fixed schedule still has coarser stages to leave: only its last one can stall.
    if ((adaptive || used_ell == scheduledEll(p.max_iterations)) &&
        stall.stalls(used_ell, s.F, T)) {
      T = stall.best();
      result.stalled = true;
      result.status = SolverStatus::kConverged;
      break;
    }

    Vector6d g;
    g << s.omega, s.v;
    const Vector6d xi = direction.next(g, p.direction);
    t0 = Clock::now();
    // The step-size model holds for any direction: its root is a line search along xi.
    const StepSums st = kernel.stepSums(xi.head<3>(), xi.tail<3>());
    const double step = solveStep(st.B, st.C, st.D, st.E, p.min_step, p.max_step);
    result.ms_step += msSince(t0);
    const Eigen::Isometry3d dT = expSE3(-step * xi);
    if (!dT.matrix().allFinite()) {
      result.status = SolverStatus::kNotFinite;
      break;
    }
    T = normalized(dT * T);
    IterationTrace trace{used_ell, ls.ell_max, step, step * xi.norm(), s.F, s.nnz};

    if (adaptive) {
      t0 = Clock::now();
      // dJ/dl from the pairs of this iteration, at the length-scale they were found with.
      const bool reference = p.ell_update == EllUpdate::kReference;
      const SelfSums xx = selfKernelSums(fixed, ls.ell, p);
      const SelfSums yy = selfKernelSums(moving, ls.ell, p, reference ? int(fixed.size()) : 0);
      if (updateLengthScale(ls, lengthScaleGradient(xx, yy, s, ls.ell), p)) {
        ++result.ell_bound_iterations;
      }
      result.ms_ell += msSince(t0);
    }
    trace.ell_max = ls.ell_max;
    result.trace.push_back(trace);
    if (step * xi.norm() < p.eps_transform) {
      result.status = SolverStatus::kConverged;
      ++it;
      break;
    }
  }
  result.ell_max_reductions = ls.reductions;
  result.iterations = it;
  result.transform = T;
  result.list_builds = kernel.candidateListBuilds();

  // Final figures at the returned transform.
  const double final_ell = adaptive ? ls.ell : scheduledEll(it);
  const CrossSums& s = kernel.evaluate(T, final_ell);
  result.ell = final_ell;
  result.ell_at_bound = adaptive && ls.pinned(p);
  result.nnz = std::size_t(s.nnz);
  result.matched_fraction = double(s.matched) / double(std::max<std::size_t>(moving.size(), 1));
  result.objective = s.F;
  const SelfSums xx = selfKernelSums(fixed, final_ell, p);
  const SelfSums yy = selfKernelSums(moving, final_ell, p);
  result.inner_product = xx.sum > 0 && yy.sum > 0 ? s.F / std::sqrt(xx.sum * yy.sum) : 0.0;
  result.hessian = kernel.curvature();
  if (!T.matrix().allFinite()) {
    result.status = SolverStatus::kNotFinite;
    result.transform = guess.matrix().allFinite() ? guess : Eigen::Isometry3d::Identity();
  }
  result.ms_total = msSince(t_start);
  return result;
}

}  // namespace acvo
