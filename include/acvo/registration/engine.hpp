// What every registration engine is to the odometry: it prepares a frame's cloud once (search
// structures; more when the cloud becomes a reference that later frames are registered to),
// registers a moving cloud to a fixed one from a guess, and says how well the result is known.
// Two engines implement it: coarse_to_fine (the default, registration/coarse_to_fine.hpp) and
// paper (A-CVO and CVO, registration/paper.hpp); makeRegistrationEngine picks one by name.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/math/se3.hpp"
#include "acvo/params.hpp"

namespace acvo {

enum class SolverStatus { kConverged, kMaxIterations, kTooFewPoints, kNotFinite };
std::string toString(SolverStatus s);

// What one iteration did (kept for tests, benchmarks and diagnosis; a few doubles each).
struct IterationTrace {
  double ell = 0.0;        // length-scale used by the iteration
  double ell_max = 0.0;    // ell_max after the iteration's update (paper engine)
  double step = 0.0;       // step size t (1 for a Gauss-Newton step)
  double change = 0.0;     // the SE(3) change of the iteration
  double objective = 0.0;  // F before the update
  std::int64_t nnz = 0;
};

// The default engine's own figures at its last iteration (registration/coarse_to_fine.hpp).
struct CoarseToFineFigures {
  // The photometric term's brightness of the moving frame against the reference's (its grey
  // values are compared times this), and the vignetting it measured: exp(vignetting rho) the
  // camera's falloff towards the corners, rho the squared distance from the principal point in
  // focal lengths. 1 and 0 without the term.
  double brightness_gain = 1.0;
  double vignetting = 0.0;
  // The dense point-to-plane term's weight (DepthGrid::weight: 0 where the depth's noise does
  // not average away or its stamp is not the colour's); NaN with the term off.
  double dense_weight = std::numeric_limits<double>::quiet_NaN();
};

// The paper engine's own figures (registration/paper.hpp).
struct PaperFigures {
  bool ell_at_bound = false;     // final ell pinned at ell_min or at the (shrunk) ell_max
  int ell_bound_iterations = 0;  // iterations that ended with ell pinned at a bound
  int ell_max_reductions = 0;    // times ell reached ell_max and the bound shrank
  double inner_product = 0.0;    // <f_X, h.f_Z> / (|f_X| |f_Z|), in [0, 1]
  double ms_step = 0.0;          // the step-size passes
  double ms_ell = 0.0;           // the length-scale updates
};

// The outcome of one registration.
struct SolverResult {
  // Maps points of the moving (current) cloud into the fixed (reference) cloud's frame.
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  SolverStatus status = SolverStatus::kTooFewPoints;
  int iterations = 0;
  double ell = 0.0;     // final spatial length-scale
  std::size_t nnz = 0;  // kept kernel pairs at the returned transform
  // Fraction of the moving points with at least one kept pair at the returned transform: how
  // much of this frame found something to hold on to in the reference.
  double matched_fraction = 0.0;
  double objective = 0.0;  // F at the optimum
  // Curvature of F at the optimum w.r.t. a left perturbation (omega, v) of the transform, 6x6,
  // negative semi-definite at a maximum: its negative is the information of the registration.
  Matrix6d hessian = Matrix6d::Zero();
  // Why the engine found this registration hard to trust (empty when it did not): the
  // odometry judges such a frame hard to track.
  std::string hard;
  int list_builds = 0;  // candidate-list rebuilds
  // The figures of the engine that registered (the other is empty).
  std::optional<CoarseToFineFigures> coarse_to_fine;
  std::optional<PaperFigures> paper;
  std::vector<IterationTrace> trace;
  // Time per stage, milliseconds.
  double ms_total = 0.0;
  double ms_neighbours = 0.0;  // pair search, kernel and the sums of each iteration
};

// The registering engine's own figures by name, for logs and messages: coarse_to_fine's
// brightness_gain, vignetting and dense_weight, or the paper's ell_at_bound (0 or 1),
// ell_max_reductions and inner_product; none when the engine did not run.
std::vector<std::pair<std::string, double>> engineFigures(const SolverResult& s);

enum class AlignStages { kAll, kCoarse, kFinest };

// One registration run as kCoarse then kFinest: the finest stage's result, with the iterations,
// trace and times of both.
SolverResult combinedStages(const SolverResult& coarse, SolverResult finest);

// A frame's cloud with what an engine built for it once. Each engine makes its own kind
// (a derived type) and only ever receives the kind it made.
struct PreparedCloud {
  virtual ~PreparedCloud() = default;
  LabelledCloud cloud;
  bool reference = false;  // what a cloud registered *to* needs is built too
  double ms_prepare = 0.0;

  std::size_t size() const { return cloud.size(); }
};

class RegistrationEngine {
 public:
  virtual ~RegistrationEngine() = default;
  // A frame's cloud with its per-frame structures; `as_reference`: also what a reference needs.
  virtual std::shared_ptr<PreparedCloud> prepare(LabelledCloud cloud, bool as_reference) const = 0;
  // Builds what a cloud registered *to* needs, once (a keyframe when it becomes one); returns
  // the milliseconds it took (0 when already done).
  virtual double prepareReference(PreparedCloud& cloud) const = 0;
  // Registers `moving` onto `fixed` (a reference) starting from `guess`. `stages`: all of them,
  // or the ones before the finest and the finest alone, for a caller that changes the moving
  // cloud in between (Odometry moves the depth to the colour's time again by the motion the
  // first found); an engine without stages (staged() false) runs whole for every value.
  virtual SolverResult align(const PreparedCloud& fixed, const PreparedCloud& moving,
                             const Eigen::Isometry3d& guess, AlignStages stages) const = 0;
  SolverResult align(const PreparedCloud& fixed, const PreparedCloud& moving,
                     const Eigen::Isometry3d& guess) const {
    return align(fixed, moving, guess, AlignStages::kAll);
  }
  virtual bool staged() const = 0;
  // Whether registrations may run on two threads at once: the engine keeps nothing from one
  // registration to the next (Odometry's window registers alongside the next frame where so).
  virtual bool reentrant() const = 0;
  // Covariance of a registered motion (T: moving -> fixed, in the fixed frame's axes); nullopt
  // when the result does not constrain every direction.
  virtual std::optional<Matrix6d> covariance(const SolverResult& s,
                                             std::size_t moving_points) const = 0;
  virtual int minPoints() const = 0;
};

// What both engines check before registering: kTooFewPoints when either cloud has fewer than
// `min_points`, kNotFinite for a guess that is not finite; nullopt when the input is usable.
// Throws std::logic_error when `fixed` was not prepared as a reference.
std::optional<SolverStatus> inputProblem(const PreparedCloud& fixed, const PreparedCloud& moving,
                                         const Eigen::Isometry3d& guess, int min_points);

// The engine Params::registration.engine names, with its parameters.
std::unique_ptr<RegistrationEngine> makeRegistrationEngine(const Params& params);

}  // namespace acvo
