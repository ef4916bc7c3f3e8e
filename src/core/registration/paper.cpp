// The paper's engine (docs/method.md §3-§4): its clouds (search grid and self-kernel pairs),
// the iteration loop of A-CVO and CVO, and its covariance.
#include "acvo/registration/paper.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "acvo/odometry/covariance.hpp"
#include "acvo/timing.hpp"

namespace acvo {
namespace {

double firstEll(const PaperParams& p) {
  return p.ell_policy == EllPolicy::kAdaptive ? p.ell_init : scheduledEll(0);
}

// The adaptive length-scale's update after an iteration, from the pairs it found at the
// length-scale they were found with; true when ell ends pinned at a bound.
bool adaptEll(LengthScale& ls, const PaperCloud& fixed, const PaperCloud& moving,
              const CrossSums& s, const PaperParams& p) {
  const bool reference = p.ell_update == EllUpdate::kReference;
  const SelfSums xx = selfKernelSums(fixed, ls.ell, p);
  const SelfSums yy = selfKernelSums(moving, ls.ell, p, reference ? int(fixed.size()) : 0);
  return updateLengthScale(ls, lengthScaleGradient(xx, yy, s, ls.ell, p.ell_update), p);
}

// The final figures at the returned transform.
void finish(PaperKernel& kernel, const PaperCloud& fixed, const PaperCloud& moving,
            const Eigen::Isometry3d& guess, double final_ell, const LengthScale& ls,
            const PaperParams& p, SolverResult& result) {
  const bool adaptive = p.ell_policy == EllPolicy::kAdaptive;
  PaperFigures& figures = *result.paper;
  figures.ell_max_reductions = ls.reductions;
  result.list_builds = kernel.listBuilds();
  const CrossSums& s = kernel.evaluate(result.transform, final_ell);
  result.ell = final_ell;
  figures.ell_at_bound = adaptive && ls.pinned(p);
  result.nnz = std::size_t(s.nnz);
  result.matched_fraction = double(s.matched) / double(std::max<std::size_t>(moving.size(), 1));
  result.objective = s.F;
  const SelfSums xx = selfKernelSums(fixed, final_ell, p);
  const SelfSums yy = selfKernelSums(moving, final_ell, p);
  figures.inner_product = xx.sum > 0 && yy.sum > 0 ? s.F / std::sqrt(xx.sum * yy.sum) : 0.0;
  result.hessian = kernel.curvature();
  if (ls.reductions >= p.hard_ell_reductions) {
    result.hard = "length-scale kept reaching its upper bound (" +
                  std::to_string(ls.reductions) + " reductions): weak structure";
  }
  if (!result.transform.matrix().allFinite()) {
    result.status = SolverStatus::kNotFinite;
    result.transform = guess.matrix().allFinite() ? guess : Eigen::Isometry3d::Identity();
  }
}

// The length-scale of iteration `it`: the adaptive one, or the schedule's (its first step at
// the length-scale carried over from the last registration, where there is one).
double usedEll(const PaperParams& p, const LengthScale& ls, double carried_ell, int it) {
  const bool adaptive = p.ell_policy == EllPolicy::kAdaptive;
  return adaptive ? ls.ell
         : carried_ell > 0.0 && scheduledEll(it) == scheduledEll(0) ? carried_ell
                                                                     : scheduledEll(it);
}

// Where the gradient ends the iteration: not finite, or under eps_gradient (converged).
std::optional<SolverStatus> gradientStop(const CrossSums& s, const PaperParams& p) {
  if (!s.omega.allFinite() || !s.v.allFinite()) return SolverStatus::kNotFinite;
  if (s.omega.norm() < p.eps_gradient && s.v.norm() < p.eps_gradient) {
    return SolverStatus::kConverged;
  }
  return std::nullopt;
}

// The step length along the gradient xi (solveStep on the kernel's step sums there), its time
// added to the figures' ms_step.
double stepLength(const PaperKernel& kernel, const Vector6d& xi, const PaperParams& p,
                  SolverResult& result) {
  const auto t0 = Clock::now();
  const StepSums st = kernel.stepSums(xi.head<3>(), xi.tail<3>());
  const double step = solveStep(st.B, st.C, st.D, st.E, p.min_step, p.max_step);
  result.paper->ms_step += msSince(t0);
  return step;
}

}  // namespace

std::shared_ptr<PaperCloud> preparePaper(LabelledCloud cloud, const PaperParams& p,
                                         bool as_reference) {
  const auto t0 = Clock::now();
  auto out = std::make_shared<PaperCloud>();
  out->cloud = std::move(cloud);
  // Self pairs serve the length-scale update and the inner product, found once per frame
  // within the radius of the largest length-scale.
  const double ell = largestEll(p);
  const double r2 = spatialRadius2(ell, p.sigma, p.sparsification);
  out->grid = VoxelGrid(out->cloud.points, gridCell(ell, p.sigma, p.sparsification));
  const KernelConstants k = kernelConstants(p.sigma, p.color_ell, p.color_sigma, p.sparsification);
  const auto& pts = out->cloud.points;
  const auto& labels = out->cloud.labels;
  for (int i = 0; i < int(pts.size()); ++i) {
    out->grid.forEachCandidate(pts[std::size_t(i)], [&](int j, const Eigen::Vector3f& x) {
      if (j <= i) return;
      const float d2 = (pts[std::size_t(i)] - x).squaredNorm();
      if (!(d2 < r2)) return;
      const float c = colorFactor(labels[std::size_t(i)], labels[std::size_t(j)], k.color_inv,
                                  k.color_sigma2);
      // Necessary condition whatever the length-scale: the pair at distance 0 must pass.
      if (k.sigma2 * c < k.sparsification) return;
      out->self_pairs.push_back({i, j, d2, c});
    });
  }
  out->self_d2.resize(Eigen::Index(out->self_pairs.size()));
  out->self_color.resize(Eigen::Index(out->self_pairs.size()));
  for (std::size_t q = 0; q < out->self_pairs.size(); ++q) {
    out->self_d2[Eigen::Index(q)] = out->self_pairs[q].d2;
    out->self_color[Eigen::Index(q)] = out->self_pairs[q].color;
  }
  out->ms_prepare = msSince(t0);
  out->reference = as_reference;
  return out;
}

SolverResult alignPaper(const PaperCloud& fixed, const PaperCloud& moving,
                        const Eigen::Isometry3d& guess, const PaperParams& p, double carried_ell) {
  const auto t_start = Clock::now();
  SolverResult result;
  result.paper.emplace();
  result.transform = guess;
  result.ell = firstEll(p);
  if (const auto problem = inputProblem(fixed, moving, guess, p.min_points)) {
    result.status = *problem;
    if (*problem == SolverStatus::kNotFinite) result.transform = Eigen::Isometry3d::Identity();
    result.ms_total = msSince(t_start);
    return result;
  }

  PaperKernel kernel(fixed.cloud, moving.cloud, fixed.grid, p);
  const bool adaptive = p.ell_policy == EllPolicy::kAdaptive;
  Eigen::Isometry3d T = guess;
  LengthScale ls{p.ell_init, p.ell_max};
  result.status = SolverStatus::kMaxIterations;
  int it = 0;
  for (; it < p.max_iterations; ++it) {
    const double used_ell = usedEll(p, ls, carried_ell, it);
    auto t0 = Clock::now();
    const CrossSums& s = kernel.evaluate(T, used_ell);
    result.ms_neighbours += msSince(t0);
    if (const auto stop = gradientStop(s, p)) {
      result.status = *stop;
      break;
    }
    Vector6d xi;
    xi << s.omega, s.v;
    const double step = stepLength(kernel, xi, p, result);
    const Eigen::Isometry3d dT = expSE3(-step * xi);
    if (!dT.matrix().allFinite()) {
      result.status = SolverStatus::kNotFinite;
      break;
    }
    T = normalized(dT * T);
    IterationTrace trace{used_ell, ls.ell_max, step, step * xi.norm(), s.F, s.nnz};
    if (adaptive) {
      t0 = Clock::now();
      if (adaptEll(ls, fixed, moving, s, p)) ++result.paper->ell_bound_iterations;
      result.paper->ms_ell += msSince(t0);
    }
    trace.ell_max = ls.ell_max;
    result.trace.push_back(trace);
    if (step * xi.norm() < p.eps_transform) {
      result.status = SolverStatus::kConverged;
      ++it;
      break;
    }
  }
  result.iterations = it;
  result.transform = T;
  finish(kernel, fixed, moving, guess, adaptive ? ls.ell : scheduledEll(it), ls, p, result);
  result.ms_total = msSince(t_start);
  return result;
}

std::shared_ptr<PreparedCloud> PaperEngine::prepare(LabelledCloud cloud, bool as_reference) const {
  return preparePaper(std::move(cloud), params_, as_reference);
}

double PaperEngine::prepareReference(PreparedCloud& cloud) const {
  cloud.reference = true;
  return 0.0;
}

SolverResult PaperEngine::align(const PreparedCloud& fixed, const PreparedCloud& moving,
                                const Eigen::Isometry3d& guess, AlignStages /*stages*/) const {
  const bool carry = params_.carry_ell && params_.ell_policy == EllPolicy::kFixedSchedule;
  SolverResult r = alignPaper(static_cast<const PaperCloud&>(fixed),
                              static_cast<const PaperCloud&>(moving), guess, params_,
                              carry ? carried_ell_ : 0.0);
  if (carry && r.status != SolverStatus::kTooFewPoints) carried_ell_ = r.ell;
  return r;
}

std::optional<Matrix6d> PaperEngine::covariance(const SolverResult& s,
                                                std::size_t moving_points) const {
  // Neighbouring pairs of one point are far from independent measurements: the curvature sums
  // nnz pairs, but the information comes from the moving points (measured: without the factor
  // the flat-colour room's errors were 5x the textured room's relative to -H^-1).
  const double pairs_per_point = double(std::max<std::size_t>(s.nnz, 1)) /
                                 double(std::max<std::size_t>(moving_points, 1));
  return scaledInverseInformation(-s.hessian, params_.covariance_scale * pairs_per_point);
}

}  // namespace acvo
