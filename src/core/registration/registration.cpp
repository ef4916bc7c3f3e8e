// The engines behind one interface: picking one by name, and what their results share.
#include "acvo/registration.hpp"

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

std::unique_ptr<RegistrationEngine> makeRegistrationEngine(const Params& params) {
  if (params.registration.engine == Engine::kPaper) {
    return std::make_unique<PaperEngine>(params.paper);
  }
  return std::make_unique<CoarseToFineEngine>(params.coarse_to_fine);
}

}  // namespace acvo
