// The paper's engine (docs/method.md §3-§4): A-CVO (the length-scale learned online) and CVO
// (its fixed schedule). Each iteration moves the transform along the kernel's ascent direction
// by the step of a 4th-order model of F, then updates the length-scale. The pieces of one
// iteration are functions here, tested one by one; alignPaper strings them together.
#pragma once

#include <cmath>
#include <memory>
#include <optional>

#include <Eigen/Geometry>

#include "acvo/params.hpp"
#include "acvo/registration/engine.hpp"
#include "acvo/registration/paper_kernel.hpp"

namespace acvo {

// Step size: the smallest positive real root of 4E t^3 + 3D t^2 + 2C t + B = 0; min_step when
// there is none; capped at max_step. Double precision, degenerate leading terms handled.
double solveStep(double B, double C, double D, double E, double min_step, double max_step);

// The adaptive length-scale of one registration: ell and its upper bound, reset per frame;
// `reductions` counts the times ell reached the bound and it shrank.
struct LengthScale {
  double ell = 0.0, ell_max = 0.0;
  int reductions = 0;
  bool pinned(const PaperParams& p) const;  // at ell_min or at the (shrunk) ell_max
};

// dJ/dell of J = |f_X - h.f_Z|^2 from the self-kernel sums of both clouds and the cross sums
// of one iteration at `ell`, divided by nnz(Axx) + nnz(Ayy) - 2 nnz(A) over all rows.
// `update` descent divides only by a positive count; reference (the authors' code) by any
// non-zero one.
double lengthScaleGradient(const SelfSums& xx, const SelfSums& yy, const CrossSums& xy, double ell,
                           EllUpdate update = EllUpdate::kDescent);

// One step of ell along -gradient (descent; `reference`: +gradient, the authors' code); on
// reaching ell_max the bound shrinks by ell_reduction (never below ell_min) and ell takes it;
// ell never below ell_min. A gradient that is not finite changes nothing. Returns whether ell
// ends pinned at a bound.
bool updateLengthScale(LengthScale& ls, double gradient, const PaperParams& p);

// The length-scale of a fixed-schedule iteration, as the authors' CVO code switches it: 0.15
// for iterations 0-3, 0.10 for 4-10, 0.06 for 11-20, 0.03 from 21 on.
double scheduledEll(int iteration);

std::shared_ptr<PaperCloud> preparePaper(LabelledCloud cloud, const PaperParams& p,
                                         bool as_reference);
// `carried_ell` > 0: the fixed schedule's first stage runs at it (PaperParams::carry_ell).
SolverResult alignPaper(const PaperCloud& fixed, const PaperCloud& moving,
                        const Eigen::Isometry3d& guess, const PaperParams& p,
                        double carried_ell = 0.0);

class PaperEngine : public RegistrationEngine {
 public:
  explicit PaperEngine(const PaperParams& params) : params_(params) {}
  std::shared_ptr<PreparedCloud> prepare(LabelledCloud cloud, bool as_reference) const override;
  double prepareReference(PreparedCloud& cloud) const override;
  using RegistrationEngine::align;
  SolverResult align(const PreparedCloud& fixed, const PreparedCloud& moving,
                     const Eigen::Isometry3d& guess, AlignStages stages) const override;
  bool staged() const override { return false; }
  bool reentrant() const override { return false; }  // it carries the length-scale
  // covariance_scale * (pairs per point) * (-H)^-1: neighbouring pairs of one point are far
  // from independent measurements, the information comes from the moving points.
  std::optional<Matrix6d> covariance(const SolverResult& s,
                                     std::size_t moving_points) const override;
  int minPoints() const override { return params_.min_points; }

 private:
  PaperParams params_;
  // The final length-scale of the last registration (carry_ell): registrations run one at a
  // time (reentrant()).
  mutable double carried_ell_ = 0.0;
};

}  // namespace acvo
