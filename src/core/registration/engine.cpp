// The engines behind one interface: picking one by name, and what their results share.
#include "acvo/registration/engine.hpp"

#include <stdexcept>

#include "acvo/registration/coarse_to_fine.hpp"
#include "acvo/registration/paper.hpp"

namespace acvo {

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

SolverResult combinedStages(const SolverResult& coarse, SolverResult finest) {
  finest.iterations += coarse.iterations;
  finest.list_builds += coarse.list_builds;
  finest.trace.insert(finest.trace.begin(), coarse.trace.begin(), coarse.trace.end());
  finest.ms_total += coarse.ms_total;
  finest.ms_neighbours += coarse.ms_neighbours;
  return finest;
}

std::vector<std::pair<std::string, double>> engineFigures(const SolverResult& s) {
  if (s.coarse_to_fine) {
    const CoarseToFineFigures& f = *s.coarse_to_fine;
    return {{"brightness_gain", f.brightness_gain},
            {"vignetting", f.vignetting},
            {"dense_weight", f.dense_weight}};
  }
  if (s.paper) {
    const PaperFigures& f = *s.paper;
    return {{"ell_at_bound", f.ell_at_bound ? 1.0 : 0.0},
            {"ell_max_reductions", double(f.ell_max_reductions)},
            {"inner_product", f.inner_product}};
  }
  return {};
}

std::optional<SolverStatus> inputProblem(const PreparedCloud& fixed, const PreparedCloud& moving,
                                         const Eigen::Isometry3d& guess, int min_points) {
  if (int(fixed.size()) < min_points || int(moving.size()) < min_points) {
    return SolverStatus::kTooFewPoints;
  }
  if (!fixed.reference) throw std::logic_error("align: the fixed cloud is not a reference");
  if (!guess.matrix().allFinite()) return SolverStatus::kNotFinite;
  return std::nullopt;
}

std::unique_ptr<RegistrationEngine> makeRegistrationEngine(const Params& params) {
  if (params.registration.engine == Engine::kPaper) {
    return std::make_unique<PaperEngine>(params.paper);
  }
  return std::make_unique<CoarseToFineEngine>(params.coarse_to_fine);
}

}  // namespace acvo
