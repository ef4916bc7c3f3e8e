// One A-CVO / CVO registration (docs/method.md §3-§4): maximise the RKHS inner product of two
// labelled clouds over SE(3), with a fixed length-scale schedule or the adaptive one.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "acvo/cross_kernel.hpp"
#include "acvo/kernel.hpp"
#include "acvo/params.hpp"
#include "acvo/se3.hpp"

namespace acvo {

enum class SolverStatus { kConverged, kMaxIterations, kTooFewPoints, kNotFinite };
std::string toString(SolverStatus s);

// What one iteration did (kept for tests, benchmarks and diagnosis; a few doubles each).
struct IterationTrace {
  double ell = 0.0;        // length-scale used by the iteration
  double ell_max = 0.0;    // ell_max after the iteration's update
  double step = 0.0;       // step size t
  double change = 0.0;     // t |xi|: the SE(3) change of the iteration
  double objective = 0.0;  // F before the update
  std::int64_t nnz = 0;
};

struct SolverResult {
  // Maps points of the moving (current) cloud into the fixed (previous) cloud's frame.
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  SolverStatus status = SolverStatus::kTooFewPoints;
  int iterations = 0;         // main-stage iterations
  int coarse_iterations = 0;  // coarse-stage iterations (SolverParams::coarse_ell)
  // Stopped by the stall rule (SolverParams::stall_iterations): the transform is the best
  // iterate at the final length-scale, not the last one.
  bool stalled = false;
  int list_builds = 0;           // candidate-list rebuilds of the main stage
  double ell = 0.0;              // final spatial length-scale
  bool ell_at_bound = false;     // final ell pinned at ell_min or at the (shrunk) ell_max
  int ell_bound_iterations = 0;  // iterations that ended with ell pinned at a bound
  // Times ell reached ell_max and the bound was reduced: the length-scale gradient kept asking
  // for a wider kernel, the sign of weak structure (the paper's "hard to track" signal).
  int ell_max_reductions = 0;
  std::size_t nnz = 0;  // kept cross-kernel entries at the last iteration
  // Fraction of the moving points with at least one kept pair at the returned transform: how
  // much of this frame found something to hold on to in the reference.
  double matched_fraction = 0.0;
  double inner_product = 0.0;  // <f_X, h.f_Z> / (|f_X| |f_Z|), in [0, 1]
  // Curvature of the objective F at the optimum w.r.t. a left perturbation
  // (omega, v) of the transform, 6x6, negative semi-definite at a maximum.
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
  double objective = 0.0;  // F at the optimum
  std::vector<IterationTrace> trace;
  // Time per stage, milliseconds.
  double ms_total = 0.0;
  double ms_neighbours = 0.0;  // cross-pair search + kernel + gradient pass
  double ms_step = 0.0;        // step-size pass
  double ms_ell = 0.0;         // length-scale update
};

// Registers `moving` onto `fixed` starting from `guess`. Both clouds must have been prepared
// (their self-kernels and search grids built, see kernel.hpp) with the same parameters.
SolverResult align(const PreparedCloud& fixed, const PreparedCloud& moving,
                   const Eigen::Isometry3d& guess, const SolverParams& params);

// Step size: the smallest positive real root of 4E t^3 + 3D t^2 + 2C t + B = 0; min_step when
// there is none; capped at max_step. Double precision, degenerate leading terms handled.
double solveStep(double B, double C, double D, double E, double min_step, double max_step);

// Search direction of a conjugate-gradient iteration (Polak-Ribiere+) from the gradient g, the
// previous gradient and the previous direction; always an ascent direction (d.g > 0), g itself
// when the previous iteration gives nothing to build on.
Vector6d conjugateDirection(const Vector6d& g, const Vector6d& g_prev, const Vector6d& d_prev);

// A coarse_to_fine Gauss-Newton step (a left increment, se(3)) extended along its direction:
// the steps of the minorise-maximise iteration shrink geometrically (ratio 0.4-0.7 per
// iteration on real frames), so when `step` points the way `previous` did (cosine above 0.9)
// and is shorter by a ratio rho < 1, the rest of that geometric series is taken at once:
// step / (1 - min(rho, max_ratio)). `step` itself otherwise, and when max_ratio is 0.
Vector6d extrapolatedStep(const Vector6d& step, const Vector6d& previous, double max_ratio);

// The adaptive length-scale of one registration (A-CVO, docs/method.md): ell and its upper
// bound, reset per frame; `reductions` counts the times ell reached the bound and it shrank.
struct LengthScale {
  double ell = 0.0, ell_max = 0.0;
  int reductions = 0;
  bool pinned(const SolverParams& p) const;  // at ell_min or at the (shrunk) ell_max
};

// dJ/dell of J = |f_X - h.f_Z|^2 from the self-kernel sums of both clouds and the cross sums
// of one iteration at `ell`, divided by nnz(Axx) + nnz(Ayy) - 2 nnz(A) when that is positive.
double lengthScaleGradient(const SelfSums& xx, const SelfSums& yy, const CrossSums& xy, double ell);

// One step of ell along -gradient (descent; `reference`: +gradient, the authors' code); on
// reaching ell_max the bound shrinks by ell_reduction (never below ell_min) and ell takes it;
// ell never below ell_min. A gradient that is not finite changes nothing. Returns whether ell
// ends pinned at a bound.
bool updateLengthScale(LengthScale& ls, double gradient, const SolverParams& p);

// The stall rule (SolverParams::stall_iterations): remembers the best objective seen at the
// current length-scale; stalls() says when `patience` iterations in a row at that length-scale
// brought nothing better (best() is then the transform to keep). Never stalls for patience 0.
class StallTracker {
 public:
  explicit StallTracker(int patience) : patience_(patience) {}
  bool stalls(double ell, double F, const Eigen::Isometry3d& T);
  const Eigen::Isometry3d& best() const { return best_T_; }

 private:
  int patience_;
  double ell_ = -1.0, best_F_ = -INFINITY;
  Eigen::Isometry3d best_T_ = Eigen::Isometry3d::Identity();
  int since_best_ = 0;
};

// The direction of each iteration from its gradient: the gradient itself, or conjugate
// gradient (conjugateDirection) from the second iteration on.
class SearchState {
 public:
  Vector6d next(const Vector6d& gradient, SearchDirection kind);

 private:
  bool started_ = false;
  Vector6d g_prev_ = Vector6d::Zero(), d_prev_ = Vector6d::Zero();
};

// The length-scale for a fixed-schedule iteration (CVO: 0.15, 0.10 after 2, 0.06 after 9,
// 0.03 after 19).
double scheduledEll(int iteration);

}  // namespace acvo
