// Every parameter of the method in one struct. The defaults are the ones measured best on real
// Kinect frames (config/acvo.yaml says how); paperParams() gives the paper's A-CVO
// (config/paper.yaml). One table (visitParams) names each field once; the YAML loader, the ROS
// parameter loader and the documentation all walk that table.
#pragma once

#include <string>

namespace acvo {

enum class EllPolicy { kAdaptive, kFixedSchedule, kCoarseToFine };
enum class EllUpdate { kDescent, kReference };
enum class InitialGuess { kConstantVelocity, kIdentity };
enum class SearchDirection { kConjugateGradient, kGradient };
enum class Reference { kKeyframe, kPreviousFrame };

struct SelectionParams {
  int target_points = 4000;    // semi-dense cloud size the selector aims at (paper: 3000)
  double min_depth = 0.1;      // m; points outside [min_depth, max_depth] are dropped
  double max_depth = 4.0;      // m (paper: 6; Kinect depth beyond 4 m is too coarse to help)
  bool canny_fallback = true;  // add Canny edge pixels when fewer than target/3 were selected
};

struct SolverParams {
  // coarse_to_fine (not in the paper, the default: see alignLevels in solver.cpp), adaptive
  // (A-CVO) or fixed_schedule (CVO).
  EllPolicy ell_policy = EllPolicy::kCoarseToFine;
  EllUpdate ell_update = EllUpdate::kDescent;  // descent (paper) or reference (authors' code)
  // Direction of each iteration: the gradient (paper) or nonlinear conjugate gradient
  // (Polak-Ribiere+, not in the paper; measured: 2.5-3x fewer iterations, see config/acvo.yaml).
  SearchDirection direction = SearchDirection::kConjugateGradient;
  // m, initial spatial length-scale (reset per frame); coarse_to_fine: its first level
  double ell_init = 0.04;
  double ell_min = 0.0045;  // m; coarse_to_fine: its last level (paper: 0.0391)
  double ell_max = 0.15;    // m (only shrinks within a frame, reset per frame)
  double ell_step = 0.3;    // gamma_l, step of the length-scale update
  // lambda_l, factor applied to ell_max when ell reaches it (paper: 0.7); coarse_to_fine: the
  // ratio of one level's length-scale to the previous one's
  double ell_reduction = 0.25;
  double sigma = 0.1;        // spatial signal std
  double color_ell = 0.1;    // colour length-scale (paper 0.1; measured, see config/acvo.yaml)
  double color_sigma = 1.0;  // colour signal std
  // a_ij below this are dropped. Paper: 8.315e-3 = 0.83 sigma^2, which keeps only pairs within
  // 0.61 ell (a flat-topped kernel); 1.1e-4 = sigma^2 exp(-4.5) keeps the Gaussian to 3 ell.
  double sparsification = 1.1e-4;
  double eps_transform = 1e-5;  // stop when t*|xi| < eps_transform
  double eps_gradient = 5e-5;   // stop when |omega| < eps and |v| < eps
  double min_step = 0.2;        // step when the cubic has no positive root
  double max_step = 0.8;        // cap on the step
  double omega_scale = 7.0;     // c: omega = (1/c) sum a (x cross y)
  double v_scale = 7.0;         // d: v = (1/d) sum a (y - x)
  int max_iterations = 200;     // reference code: 2000 (too many for real time)
  // Stop when F has not improved for this many iterations at an unchanged length-scale and
  // return the best transform seen (not in the paper: with ell pinned at ell_min the iterates
  // otherwise jitter around the optimum until the cap). 0 = off.
  int stall_iterations = 6;
  // Coarse stage (not in the paper): before the main iterations, a few CVO iterations with a
  // wide fixed length-scale on a subset of the moving points widen the basin of convergence
  // (a 5 degree rotation moves points 17 cm at 2 m, beyond the reach of ell_max). 0 = off.
  double coarse_ell = 0.4;     // m
  int coarse_points = 500;     // moving points used by the coarse stage (evenly strided)
  int coarse_iterations = 20;  // iteration cap of the coarse stage
  int min_points = 30;         // fewer points in either cloud -> status too_few_points
  // coarse_to_fine only (see config/acvo.yaml for the measurements):
  // Range-dependent length-scale: a point at depth z uses ell * z / ell_depth_reference (the
  // factor clamped to [0.5, 3]), so that the kernel spans the same pixels near and far. 0 = off.
  double ell_depth_reference = 1.0;  // m
  // Depth noise sigma_z = depth_noise * z^2 (Kinect-like; both points' share): the kernel is
  // stretched along the viewing ray by it, so that depth noise does not outweigh the lateral
  // position of a point. 0 = isotropic.
  double depth_noise = 0.0025;  // 1/m
  int level_points = 200;       // moving points at the first level (x ell_init / ell after)
  int level_iterations = 10;    // Gauss-Newton iterations per level, at most
  // Next level when an iteration moves less than level_eps * ell / ell_min (rad and m): the
  // finest level to level_eps, a coarser one in proportion to its length-scale.
  double level_eps = 2e-4;
  // Steps that keep their direction and shrink by a ratio rho are extended by 1 / (1 - rho),
  // rho capped at this (extrapolatedStep; 0 = plain Gauss-Newton steps).
  double level_acceleration = 0.5;
};

struct OdometryParams {
  InitialGuess initial_guess = InitialGuess::kConstantVelocity;
  // What each frame is registered to (not in the paper, which registers to the previous frame):
  // a keyframe, kept while the frames still overlap it (a camera that stands still or sways
  // then collects no drift), or the previous frame. See odometry.hpp.
  Reference reference = Reference::kKeyframe;
  // keyframe only: a frame registered to the keyframe becomes the next keyframe when fewer
  // than this fraction of its points found a kernel partner in the keyframe, when its motion
  // from the keyframe exceeds keyframe_translation or keyframe_rotation, or when it was hard
  // to track.
  double keyframe_matched_fraction = 0.5;
  double keyframe_translation = 0.05;  // m
  double keyframe_rotation = 2.0;      // deg
  int threads = 0;                     // 0 = all cores
  // Tracking judgement (see odometry.hpp): lost when fewer than this fraction of the frame's
  // points found a kernel partner at the solution (nothing in common), or when a frame-to-frame
  // motion exceeds the limits below; hard to track below hard_matched_fraction.
  double lost_matched_fraction = 0.1;
  double hard_matched_fraction = 0.25;
  double max_translation = 0.3;  // m per frame
  double max_rotation = 20.0;    // deg per frame
  int hard_ell_reductions = 3;   // hard to track when ell_max was reduced this often in a frame
  // Relative-motion covariance = covariance_scale * (pairs per point) * (-H)^-1, H the curvature
  // of the objective at the optimum; see odometry.hpp (calibration in config/acvo.yaml).
  double covariance_scale = 3.0e-7;
  // While tracking is lost the camera may move unseen: the held pose's covariance grows by
  // (lost_speed * t)^2 and (lost_angular_speed * t)^2, t the time since the last tracked frame
  // (a hand-held camera: 0.35 m/s and up to 100 deg/s on TUM fr3/teddy).
  double lost_speed = 1.0;           // m/s
  double lost_angular_speed = 90.0;  // deg/s
};

struct Params {
  SelectionParams selection;
  SolverParams solver;
  OdometryParams odometry;
};

std::string toString(EllPolicy v);
std::string toString(EllUpdate v);
std::string toString(InitialGuess v);
std::string toString(SearchDirection v);
std::string toString(Reference v);
// Throw std::invalid_argument listing the accepted values.
void fromString(const std::string& s, EllPolicy& v);
void fromString(const std::string& s, EllUpdate& v);
void fromString(const std::string& s, InitialGuess& v);
void fromString(const std::string& s, SearchDirection& v);
void fromString(const std::string& s, Reference& v);

// Calls visit(section, name, field) for every parameter; field is int&, double&, bool& or one
// of the enums above. Sections: "selection", "solver", "odometry".
template <typename Params_, typename Visitor>
void visitParams(Params_& p, Visitor&& visit) {
  visit("selection", "target_points", p.selection.target_points);
  visit("selection", "min_depth", p.selection.min_depth);
  visit("selection", "max_depth", p.selection.max_depth);
  visit("selection", "canny_fallback", p.selection.canny_fallback);
  visit("solver", "ell_policy", p.solver.ell_policy);
  visit("solver", "ell_update", p.solver.ell_update);
  visit("solver", "direction", p.solver.direction);
  visit("solver", "ell_init", p.solver.ell_init);
  visit("solver", "ell_min", p.solver.ell_min);
  visit("solver", "ell_max", p.solver.ell_max);
  visit("solver", "ell_step", p.solver.ell_step);
  visit("solver", "ell_reduction", p.solver.ell_reduction);
  visit("solver", "sigma", p.solver.sigma);
  visit("solver", "color_ell", p.solver.color_ell);
  visit("solver", "color_sigma", p.solver.color_sigma);
  visit("solver", "sparsification", p.solver.sparsification);
  visit("solver", "eps_transform", p.solver.eps_transform);
  visit("solver", "eps_gradient", p.solver.eps_gradient);
  visit("solver", "min_step", p.solver.min_step);
  visit("solver", "max_step", p.solver.max_step);
  visit("solver", "omega_scale", p.solver.omega_scale);
  visit("solver", "v_scale", p.solver.v_scale);
  visit("solver", "max_iterations", p.solver.max_iterations);
  visit("solver", "stall_iterations", p.solver.stall_iterations);
  visit("solver", "coarse_ell", p.solver.coarse_ell);
  visit("solver", "coarse_points", p.solver.coarse_points);
  visit("solver", "coarse_iterations", p.solver.coarse_iterations);
  visit("solver", "min_points", p.solver.min_points);
  visit("solver", "ell_depth_reference", p.solver.ell_depth_reference);
  visit("solver", "depth_noise", p.solver.depth_noise);
  visit("solver", "level_points", p.solver.level_points);
  visit("solver", "level_iterations", p.solver.level_iterations);
  visit("solver", "level_eps", p.solver.level_eps);
  visit("solver", "level_acceleration", p.solver.level_acceleration);
  visit("odometry", "initial_guess", p.odometry.initial_guess);
  visit("odometry", "threads", p.odometry.threads);
  visit("odometry", "reference", p.odometry.reference);
  visit("odometry", "keyframe_matched_fraction", p.odometry.keyframe_matched_fraction);
  visit("odometry", "keyframe_translation", p.odometry.keyframe_translation);
  visit("odometry", "keyframe_rotation", p.odometry.keyframe_rotation);
  visit("odometry", "lost_matched_fraction", p.odometry.lost_matched_fraction);
  visit("odometry", "hard_matched_fraction", p.odometry.hard_matched_fraction);
  visit("odometry", "max_translation", p.odometry.max_translation);
  visit("odometry", "max_rotation", p.odometry.max_rotation);
  visit("odometry", "hard_ell_reductions", p.odometry.hard_ell_reductions);
  visit("odometry", "covariance_scale", p.odometry.covariance_scale);
  visit("odometry", "lost_speed", p.odometry.lost_speed);
  visit("odometry", "lost_angular_speed", p.odometry.lost_angular_speed);
}

// The paper's A-CVO (adaptive length-scale, its table of constants, 3000 points up to 6 m) with
// this package's speed-ups for it: conjugate-gradient direction, stall rule, coarse stage
// (config/paper.yaml; set direction: gradient, stall_iterations: 0, coarse_ell: 0 for the
// paper's letter).
Params paperParams();

// Empty when the values are consistent; otherwise a message naming the offending parameter.
std::string validate(const Params& p);

// Loads a YAML file with the sections above. Unknown sections or keys, wrong value types and
// inconsistent values throw std::runtime_error naming the file and the key.
Params loadParams(const std::string& path);
// Applies a YAML text on top of `base` (same rules); used by loadParams and by tests.
Params parseParams(const std::string& yaml_text, const Params& base = Params(),
                   const std::string& source_name = "<string>");

}  // namespace acvo
