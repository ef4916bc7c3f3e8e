// The default engine's levels (docs/method.md §6): its clouds, the level-by-level Gauss-Newton
// iteration, and its covariance.
#include "acvo/registration/coarse_to_fine.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include <Eigen/Cholesky>

#include "acvo/odometry/covariance.hpp"
#include "acvo/timing.hpp"

namespace acvo {
namespace {

// Steps this well aligned (cosine) are taken as one linear convergence (extrapolatedStep).
constexpr double kAlignedSteps = 0.9;

// One Gauss-Newton step on a quadratic: the left increment H^-1 g. Identity when it constrains
// nothing.
Eigen::Isometry3d levelStep(const Matrix6d& H, const Vector6d& g) {
  const Eigen::LDLT<Matrix6d> ldlt(H);
  if (ldlt.info() != Eigen::Success || !(H.trace() > 0.0)) return Eigen::Isometry3d::Identity();
  const Vector6d xi = ldlt.solve(g);
  return xi.allFinite() ? expSE3(xi) : Eigen::Isometry3d::Identity();
}

// The direct terms of a level, when it has them.
struct LevelDirect {
  const DirectImages* reference = nullptr;
  const DirectImages* moving = nullptr;
  const LabelledCloud* moving_cloud = nullptr;
  const LabelledCloud* reference_cloud = nullptr;
};

// The step's quadratic: the kernel's, plus the direct terms' where the level has them. Returns
// the factor that took the kernel's sums to the terms' units.
double addDirectTerms(const LevelSums& s, double ell, const LevelDirect& direct,
                      const CoarseToFineParams& p, const Eigen::Isometry3d& T, Matrix6d& H,
                      Vector6d& g, Brightness& brightness, PlaneMemo& planes) {
  // The kernel's quadratic is sum a_ij (x_i - y)^T W (x_i - y) / 2 ell_j^2 but for the factor
  // ell^2 its sums leave out: divided by ell^2 and by the mean kernel mass of a matched point,
  // each matched point weighs as one position known to ell_j, the scale the terms below are in.
  const double mass = s.F / double(std::max<std::int64_t>(s.matched, 1));
  const double to_units = mass > 0.0 ? 1.0 / (ell * ell * mass) : 0.0;
  if (!(to_units > 0.0)) return 0.0;
  const double share = p.depth_led ? kDepthLedKernelShare : 1.0;
  H = s.H * (to_units * share);
  g = s.g * (to_units * share);
  const std::vector<Landing> landed =
      landings(*direct.reference, *direct.moving, *direct.moving_cloud, T);
  if (p.photometric) {
    const DirectSums d = photometricSums(*direct.reference, *direct.moving, *direct.moving_cloud,
                                         landed, p.photometric_gain, p.photometric_vignetting,
                                         p.edge_variance, p.tukey_sigmas);
    brightness = d.brightness;
    if (p.reverse_photometric) {
      const DirectSums r = reversePhotometricSums(*direct.reference, *direct.reference_cloud,
                                                  *direct.moving, *direct.moving_cloud, T,
                                                  d.brightness, p.edge_variance, p.tukey_sigmas);
      H += (1.0 - kReverseShare) * d.H + kReverseShare * r.H;
      g += (1.0 - kReverseShare) * d.g + kReverseShare * r.g;
    } else {
      H += d.H;
      g += d.g;
    }
  }
  if (p.point_to_plane) {
    const DirectSums d =
        pointToPlaneSums(*direct.reference, landed, planeFadeNoise(p), &planes, p.tukey_sigmas);
    H += d.H;
    g += d.g;
  }
  if (p.dense_point_to_plane) {
    const DirectSums d = densePlaneSums(*direct.reference, *direct.moving, T, p.tukey_sigmas);
    H += d.H;
    g += d.g;
  }
  return to_units;
}

// Iterates one level from T; returns false when a step was not finite.
bool iterateLevel(LevelKernel& kernel, const LevelDirect& direct, double ell, double eps,
                  bool last, const CoarseToFineParams& p, Eigen::Isometry3d& T,
                  SolverResult& result) {
  Vector6d previous = Vector6d::Zero();
  PlaneMemo planes;
  for (int it = 0; it < p.level_iterations; ++it) {
    const auto t0 = Clock::now();
    const LevelSums& s = kernel.evaluate(T, ell);
    Matrix6d H = s.H;
    Vector6d g = s.g;
    // The information of the registration: the quadratic's, in the kernel's own units (those
    // covariance_scale was calibrated in).
    result.hessian = -s.H;
    if (direct.reference) {
      Brightness brightness;
      const double to_units = addDirectTerms(s, ell, direct, p, T, H, g, brightness, planes);
      result.coarse_to_fine->brightness_gain = brightness.gain;
      result.coarse_to_fine->vignetting = brightness.vignetting;
      if (to_units > 0.0) result.hessian = -H / to_units;
    }
    result.ms_neighbours += msSince(t0);
    const Eigen::Isometry3d step = levelStep(H, g);
    if (!step.matrix().allFinite()) return false;
    // The direct terms converge as Gauss-Newton does, not as the kernel's slow
    // minorise-maximise: their steps are taken as they are.
    const double acceleration = direct.reference ? 0.0 : p.level_acceleration;
    const Vector6d xi = extrapolatedStep(logSE3(step), previous, acceleration);
    const bool converged = xi.head<3>().norm() < eps && xi.tail<3>().norm() < eps;
    T = normalized(expSE3(xi) * T);
    previous = xi;
    result.trace.push_back({ell, ell, 1.0, xi.norm(), s.F, s.nnz});
    ++result.iterations;
    if (converged) break;
    if (last && it + 1 == p.level_iterations) result.status = SolverStatus::kMaxIterations;
  }
  return true;
}

// The direct terms of a level: the last level's, where the terms are on, the fixed cloud has a
// reference's images and the moving cloud its own (with the dense term's weight in `result`).
LevelDirect levelDirect(const CoarseToFineCloud& fixed, const CoarseToFineCloud& moving,
                        const CoarseToFineParams& p, bool last, SolverResult& result) {
  LevelDirect direct;
  if (last && directTerms(p) && fixed.images.isReference() && !moving.images.empty()) {
    direct = {&fixed.images, &moving.images, &moving.cloud, &fixed.cloud};
    if (p.dense_point_to_plane) {
      result.coarse_to_fine->dense_weight = denseWeight(fixed.images, moving.images);
    }
  }
  return direct;
}

// Final figures on the full cloud at the finest length-scale: the last level's kernel at its
// last iterate, a step short of T (a step under eps when converged; one more kernel pass at T
// gave the same trajectories on teddy200).
void setFinalFigures(const LevelKernel& kernel, std::size_t moving_points, SolverResult& result) {
  const LevelSums& s = kernel.last();
  result.nnz = std::size_t(s.nnz);
  result.matched_fraction = double(s.matched) / double(std::max<std::size_t>(moving_points, 1));
  result.objective = s.F;
  // result.hessian: the information of the last iterate's quadratic (the Gauss-Newton matrix
  // the steps solve with); the exact curvature of the narrow kernel is no better conditioned.
  result.list_builds = kernel.listBuilds();
}

}  // namespace

double planeFadeNoise(const CoarseToFineParams& p) { return p.depth_led ? 0.0 : p.depth_noise; }

bool directTerms(const CoarseToFineParams& p) {
  return p.photometric || p.point_to_plane || p.dense_point_to_plane;
}

std::vector<double> levelElls(const CoarseToFineParams& p) {
  std::vector<double> ells;
  for (double ell = p.ell_init; ell > p.ell_min * (1.0 + 1e-9); ell *= p.ell_reduction) {
    ells.push_back(ell);
  }
  ells.push_back(p.ell_min);
  return ells;
}

Vector6d extrapolatedStep(const Vector6d& step, const Vector6d& previous, double max_ratio) {
  const double n = step.norm(), n_prev = previous.norm();
  if (!(max_ratio > 0.0) || !(n > 0.0) || !(n_prev > 0.0)) return step;
  const double ratio = n / n_prev;
  if (!(ratio < 1.0) || step.dot(previous) < kAlignedSteps * n * n_prev) return step;
  return step / (1.0 - std::min(ratio, max_ratio));
}

std::shared_ptr<CoarseToFineCloud> prepareCoarseToFine(LabelledCloud cloud,
                                                       const CoarseToFineParams& p,
                                                       bool as_reference) {
  const auto t0 = Clock::now();
  auto out = std::make_shared<CoarseToFineCloud>();
  out->cloud = std::move(cloud);
  if (directTerms(p)) {
    out->images =
        directImages(out->cloud, p.dense_point_to_plane, planeFadeNoise(p),
                     p.photometric && p.reverse_photometric, p.grey_smoothing,
                     p.exact_depth_grid_stride);
  }
  out->ms_prepare = msSince(t0);
  if (as_reference) prepareCoarseToFineReference(*out, p);
  return out;
}

double prepareCoarseToFineReference(CoarseToFineCloud& cloud, const CoarseToFineParams& p) {
  if (cloud.reference) return 0.0;
  const auto t0 = Clock::now();
  for (double ell : levelElls(p)) {
    cloud.level_grids.emplace_back(cloud.cloud.points, gridCell(ell, p.sigma, p.sparsification));
  }
  addReferenceImages(cloud.images, cloud.cloud);
  cloud.reference = true;
  const double ms = msSince(t0);
  cloud.ms_prepare += ms;
  return ms;
}

SolverResult alignCoarseToFine(const CoarseToFineCloud& fixed, const CoarseToFineCloud& moving,
                               const Eigen::Isometry3d& guess, const CoarseToFineParams& p,
                               AlignStages stages) {
  const auto t_start = Clock::now();
  SolverResult result;
  result.coarse_to_fine.emplace();
  result.transform = guess;
  const std::vector<double> ells = levelElls(p);
  result.ell = ells.back();
  if (const auto problem = inputProblem(fixed, moving, guess, p.min_points)) {
    result.status = *problem;
    if (*problem == SolverStatus::kNotFinite) result.transform = Eigen::Isometry3d::Identity();
    result.ms_total = msSince(t_start);
    return result;
  }

  // Pairs per point grow with the kernel's reach: fewer moving points at the wide levels
  // (level_points at the first, in proportion to 1 / ell after it, all at the last).
  Eigen::Isometry3d T = guess;
  result.status = SolverStatus::kConverged;
  std::unique_ptr<LevelKernel> kernel;
  LabelledCloud subset;
  const int levels = int(ells.size());
  const int first = stages == AlignStages::kFinest ? levels - 1 : 0;
  const int end = stages == AlignStages::kCoarse ? levels - 1 : levels;
  if (first >= end) {
    result.ms_total = msSince(t_start);
    return result;
  }
  for (int level = first; level < end; ++level) {
    const double ell = ells[std::size_t(level)];
    const bool last = level + 1 == levels;
    const int count = int(std::min<double>(moving.size(), p.level_points * ells.front() / ell));
    kernel.reset();
    const bool strided = !last && count < int(moving.size());
    if (strided) subset = stridedSubset(moving.cloud, count);
    kernel = std::make_unique<LevelKernel>(fixed.cloud, strided ? subset : moving.cloud,
                                           fixed.level_grids[std::size_t(level)], p);
    // A level need not resolve the motion finer than its length-scale allows: the next level
    // refines it (measured: a third fewer iterations, the same accuracy).
    const double eps = p.level_eps * ell / ells.back();
    const LevelDirect direct = levelDirect(fixed, moving, p, last, result);
    if (!iterateLevel(*kernel, direct, ell, eps, last, p, T, result)) {
      result.status = SolverStatus::kNotFinite;
      result.transform = guess;
      result.ms_total = msSince(t_start);
      return result;
    }
  }
  result.transform = T;
  if (!T.matrix().allFinite()) {
    result.status = SolverStatus::kNotFinite;
    result.transform = guess;
  }
  setFinalFigures(*kernel, moving.size(), result);
  result.ms_total = msSince(t_start);
  return result;
}

std::shared_ptr<PreparedCloud> CoarseToFineEngine::prepare(LabelledCloud cloud,
                                                           bool as_reference) const {
  return prepareCoarseToFine(std::move(cloud), params_, as_reference);
}

double CoarseToFineEngine::prepareReference(PreparedCloud& cloud) const {
  return prepareCoarseToFineReference(static_cast<CoarseToFineCloud&>(cloud), params_);
}

SolverResult CoarseToFineEngine::align(const PreparedCloud& fixed, const PreparedCloud& moving,
                                       const Eigen::Isometry3d& guess, AlignStages stages) const {
  return alignCoarseToFine(static_cast<const CoarseToFineCloud&>(fixed),
                           static_cast<const CoarseToFineCloud&>(moving), guess, params_, stages);
}

std::optional<Matrix6d> CoarseToFineEngine::covariance(const SolverResult& s,
                                                       std::size_t /*moving_points*/) const {
  return scaledInverseInformation(-s.hessian, params_.covariance_scale);
}

}  // namespace acvo
