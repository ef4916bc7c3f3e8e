// Every parameter of the method, one struct per concern: the cloud (selection), which engine
// registers the clouds (registration), each engine's own (coarse_to_fine: the default; paper:
// the paper's A-CVO and CVO), and the odometry around them. The defaults are the ones measured
// best on real Kinect frames (config/acvo.yaml says how); paperParams() and cvoParams() give
// the paper's engine as the authors' code runs it (config/paper.yaml, config/cvo.yaml). One
// table (visitParams) names each field once; the YAML loader, the ROS parameter loader and the
// documentation all walk that table.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace acvo {

enum class Engine { kCoarseToFine, kPaper };
enum class EllPolicy { kAdaptive, kFixedSchedule };
enum class EllUpdate { kDescent, kReference };
enum class InitialGuess { kConstantVelocity, kIdentity };
enum class Reference { kKeyframe, kPreviousFrame };
enum class SyncDepth { kNone, kLastMotion, kOwnMotion };
enum class UnregisteredColour { kAsGiven, kResample, kResampleDepthLed };

struct SelectionParams {
  int target_points = 4000;    // semi-dense cloud size the selector aims at (paper: 3000)
  double min_depth = 0.1;      // m; points outside [min_depth, max_depth] are dropped
  double max_depth = 10.0;     // m (paper: no limit): far points pin the rotation; their coarse
                               // depth is modelled along the ray (depth_noise)
  bool canny_fallback = true;  // add Canny edge pixels when fewer than target/3 were selected
  // target_points is for a 640x480 image; another size aims at target_points times its width
  // over 640 (the square root of its pixels over 640x480's): edges, where points are chosen,
  // grow with the width, and a dense peer's cost with the pixels.
  bool scale_with_image = true;
};

struct RegistrationParams {
  // coarse_to_fine (the default; docs/method.md §6) or paper (A-CVO / CVO, §3-§4).
  Engine engine = Engine::kCoarseToFine;
};

// The default engine (docs/method.md §6): a Gaussian kernel kept to 3 ell, maximised by
// Gauss-Newton steps on its minorising quadratic at ell_init, ell_init * ell_reduction, ...
// down to ell_min, each length-scale in proportion to the point's depth and stretched along its
// viewing ray by the depth noise.
struct CoarseToFineParams {
  double ell_init = 0.04;        // m at 1 m depth: the first level
  double ell_min = 0.0045;       // m at 1 m depth: the last level
  double ell_reduction = 0.25;   // ratio of one level's length-scale to the previous one's
  double sigma = 0.1;            // spatial signal std
  double color_ell = 0.1;        // colour length-scale
  double color_sigma = 1.0;      // colour signal std
  // a_ij below this are dropped: 1.1e-4 = sigma^2 exp(-4.5) keeps the Gaussian to 3 ell.
  double sparsification = 1.1e-4;
  // A point at depth z uses ell * z / ell_depth_reference (the factor clamped to [0.5, 3]), so
  // that the kernel spans the same pixels near and far. 0 = off.
  double ell_depth_reference = 1.0;  // m
  // Depth noise sigma_z = depth_noise * z^2 (Kinect-like; both points' share): the kernel is
  // stretched along the viewing ray by it. 0 = isotropic.
  double depth_noise = 0.0025;  // 1/m
  int level_points = 200;       // moving points at the first level (x ell_init / ell after)
  int level_iterations = 10;    // Gauss-Newton iterations per level, at most
  // Next level when an iteration moves less than level_eps * ell / ell_min (rad and m).
  double level_eps = 2e-4;
  // Steps that keep their direction and shrink by a ratio rho are extended by 1 / (1 - rho),
  // rho capped at this (extrapolatedStep; 0 = plain Gauss-Newton steps).
  double level_acceleration = 0.5;
  // The last level's direct terms (docs/method.md §6), added to the kernel's quadratic: each
  // point's grey value against the reference image where it projects (photometric), and its
  // distance to the plane of the reference's depth there (point_to_plane; its weight fades to
  // none as the depth's residuals reach the depth noise above, so it counts where depth is
  // better than a Kinect's). Off: the kernel alone, as before them.
  bool photometric = true;
  // The photometric term in both directions: also each reference point's grey value against the
  // moving image where it lands (counted as one term with the forward direction). Off: forward.
  bool reverse_photometric = true;
  // The grey images are smoothed by a Gaussian of this std (px) before the photometric term
  // samples them: rendered images, sampled without anti-aliasing, have intensity steps no
  // sub-pixel shift matches; a real camera's optics blur as much. 0: as they are.
  double grey_smoothing = 0.7;
  // A grey residual's variance is its learned scale squared plus its squared gradient times this
  // (px^2): the variance of where an intensity edge lies, a pixel's quantisation (DSO's
  // gradient-dependent weight). 0: the learned scale alone.
  double edge_variance = 1.0 / 12.0;
  // Every direct term's residuals get Tukey's biweight to this many standard deviations: beyond
  // them (a person crossing the view, an occlusion) a residual no longer pulls. 0: least squares.
  double tukey_sigmas = 8.0;
  bool point_to_plane = true;
  // ... and the plane distances of the moving depth on a grid of pixels, each point a window's
  // mean (dense_point_to_plane; direct_terms.hpp, denseGrid): ICP's evidence, used only where
  // averaging pixels makes depth more precise (noise drawn per pixel, a simulator's) or where the
  // depth is exact, and only on depth taken at the colour's instant (Frame::depth_stamp:
  // a delay moves the depth by an estimated motion, whose error it would follow).
  bool dense_point_to_plane = true;
  // Pixels between the dense term's points where the depth is exact (its measured noise under a
  // tenth of depth_noise: a simulator's); every 10th pixel elsewhere.
  int exact_depth_grid_stride = 5;
  // The last level led by the depth: both point-to-plane terms at the weight their own learned
  // scales give (no fade by depth_noise, the dense term whatever its independence) and the
  // kernel's quadratic at kDepthLedKernelShare of its weight. The kernel's optimum is pulled
  // towards no motion on real Kinect depth (7-Scenes: the chain of registrations turned 0.935
  // of the reference's turn), the plane residuals measured in the reference's image are not;
  // where the colour's residuals stand beside the kernel they correct the pull, where the colour
  // is from another camera they cannot. The odometry turns it on, with photometric off, where
  // it resamples such colour.
  bool depth_led = false;
  // The photometric term measures each frame's brightness against the reference's (the median
  // ratio of their grey values at the points it compares) and compares grey values at that
  // gain: a camera's auto exposure changes the brightness from frame to frame. Off: the grey
  // values as they are.
  bool photometric_gain = true;
  // ... and the camera's vignetting, the darkening towards the image's corners that a point
  // moving across the image sees (measured the same way, per registration).
  bool photometric_vignetting = true;
  // The camera's exposure time (s). A moving camera smears each colour edge along a point's
  // image motion over it (predicted from the last frame's motion); a point whose depth changes
  // surface within that smear has the other surface's colour and is left out of both direct
  // terms. 0: the images are sharp (only the 4-neighbours' depth is checked).
  double exposure_time = 0.016;
  int min_points = 30;  // fewer points in either cloud -> status too_few_points
  // Registration covariance = covariance_scale * (-H)^-1, H the Gauss-Newton information.
  double covariance_scale = 3.0e-7;
};

// The paper's engine (docs/method.md §3-§4): gradient flow on SE(3) with the 4th-order step,
// the length-scale learned online (adaptive: A-CVO) or on CVO's fixed schedule.
struct PaperParams {
  EllPolicy ell_policy = EllPolicy::kAdaptive;  // adaptive (A-CVO) or fixed_schedule (CVO)
  // adaptive: descent (as the paper states) or reference (as the authors' code: ascent, the
  // moving cloud's self-kernel rows below the fixed cloud's size left out of the sum).
  EllUpdate ell_update = EllUpdate::kReference;
  double ell_init = 0.1;      // m, initial spatial length-scale (reset per frame)
  double ell_min = 0.0391;    // m
  double ell_max = 0.15;      // m (only shrinks within a frame, reset per frame)
  double ell_step = 0.3;      // gamma_l, step of the length-scale update
  double ell_reduction = 0.7;  // lambda_l, factor applied to ell_max when ell reaches it
  double sigma = 0.1;          // spatial signal std
  double color_ell = 0.5;      // colour length-scale (paper's table 0.1; authors' code 0.5)
  double color_sigma = 1.0;    // colour signal std
  // a_ij below this are dropped (0.8315 sigma^2: pairs within 0.61 ell, a flat-topped kernel)
  double sparsification = 8.315e-3;
  double eps_transform = 1e-5;  // stop when t*|xi| < eps_transform
  double eps_gradient = 5e-5;   // stop when |omega| < eps and |v| < eps
  double min_step = 0.2;        // step when the cubic has no positive root
  double max_step = 0.8;        // cap on the step
  double omega_scale = 7.0;     // c: omega = (1/c) sum a (x cross y)
  double v_scale = 7.0;         // d: v = (1/d) sum a (y - x)
  int max_iterations = 2000;    // as the authors' code
  // fixed_schedule: the schedule's first stage (iterations 0-3) at the previous registration's
  // final length-scale instead of 0.15, as the authors' CVO code runs (its length-scale outlives
  // the frame). The engine then keeps that length-scale between registrations.
  bool carry_ell = false;
  int min_points = 30;         // fewer points in either cloud -> status too_few_points
  // Hard to track when ell reached ell_max (and the bound shrank) this often in a frame.
  int hard_ell_reductions = 3;
  // Registration covariance = covariance_scale * (pairs per point) * (-H)^-1.
  double covariance_scale = 6.0e-4;
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
  // keyframe only: the local window (odometry/keyframe_window.hpp, docs/method.md §7.7). Each
  // new keyframe is also registered to the older keyframes in the window, and the window's poses
  // are refined together over those registrations, while the next frame is registered; the
  // frames after it go on from its refined pose. The number of keyframes in the window, the new
  // one included; 0 to 2: no window, each keyframe's pose from its registration to the one
  // before alone.
  int window_keyframes = 4;
  int threads = -1;  // -1 = all cores but one (a camera driver keeps a core), 0 = all, n = n
  // Tracking judgement (see odometry.hpp): lost when fewer than this fraction of the frame's
  // points found a kernel partner at the solution (nothing in common), or when a frame-to-frame
  // motion exceeds the limits below; hard to track below hard_matched_fraction.
  double lost_matched_fraction = 0.1;
  double hard_matched_fraction = 0.25;
  double max_translation = 0.3;  // m per frame
  double max_rotation = 20.0;    // deg per frame
  // While tracking is lost the camera may move unseen: the held pose's covariance grows by
  // (lost_speed * t)^2 and (lost_angular_speed * t)^2, t the time since the last tracked frame
  // (a hand-held camera: 0.35 m/s and up to 100 deg/s on TUM fr3/teddy).
  double lost_speed = 1.0;           // m/s
  double lost_angular_speed = 90.0;  // deg/s
  // Colour and depth taken at different times (Frame::depth_stamp), so that each point's colour
  // and position are of one instant: own_motion moves the depth to the colour's time by the
  // last frame-to-frame motion (constant velocity), then again, between the registration's
  // coarse levels and its finest, at the frame's own velocity as the coarse levels found it;
  // last_motion only the first; none pairs the two as they come.
  SyncDepth sync_depth = SyncDepth::kOwnMotion;
  // Once the colour check (ColourDepthCheck) finds the depth not registered to the colour (a
  // second camera's colour, 7-Scenes'): resample resamples each frame's colour to the depth
  // camera's focal length by the ratio the check found (withColourResampled), so that the points
  // chosen at its edges lie where the texture is; resample_depth_led also registers it without
  // the photometric term (a point's colour is still off by the cameras' baseline, a few pixels),
  // the last level led by the depth (CoarseToFineParams::depth_led); as_given uses the colour as
  // it comes, with the check's warning.
  UnregisteredColour unregistered_colour = UnregisteredColour::kResampleDepthLed;
  // Where the registered motion misses the motion guess (constant velocity) by more than
  // kSecondStartTranslation or kSecondStartRotation in one frame (odometry.hpp; more than a
  // hand-held camera's velocity changes in a frame: up to 20 mm on the real folders), the
  // finest level is run again from the guess, and that result is kept unless the first's kernel
  // value there is kSecondStartMargin times higher (kSecondStartKeptMargin within
  // kSecondStartMemory of a frame that kept one). A person crossing a third of the view can
  // pull the coarse levels, whose kernel spans both motions, into the person's motion; the
  // finest level's narrow kernel, started from the camera's own predicted motion, holds the
  // still part. A miss under those limits but unusual for the camera (kSecondStartCheckSigmas
  // times its recent velocity changes over the interval) is run again too, kept only where it
  // scores kSecondStartCheckMargin times the first (a person entering the view of a smooth
  // camera). Where no motion is known yet (the first frame, the first after a lost one) and over
  // kRestFraction of the points disagree with the reference, those points are registered alone,
  // and that result is kept where kRestMargin times as many of the image's pixels agree with it
  // (a person in view from the start). Off: the paper's single start.
  bool second_start = true;
  // Parts of the second start, each on its own (all need second_start):
  //  - second_start_check: a miss under the limits but unusual for this camera (more than
  //    kSecondStartCheckSigmas times its recent velocity changes) is run again too;
  //  - second_start_memory: within kSecondStartMemory of a kept second start the first must
  //    score kSecondStartKeptMargin times the second's to be kept (a person pulling lately);
  //  - turn_start: a turn and a translation that both miss, scoring low against the last frame,
  //    are run again from the turn with the guess's translation (a fast turn taken partly for a
  //    sideways move);
  //  - rest_start: with no motion known, the points left disagreeing are registered alone.
  bool second_start_check = true;
  bool second_start_memory = true;
  bool turn_start = true;
  bool rest_start = true;
};

struct Params {
  SelectionParams selection;
  RegistrationParams registration;
  CoarseToFineParams coarse_to_fine;
  PaperParams paper;
  OdometryParams odometry;
};

std::string toString(Engine v);
std::string toString(EllPolicy v);
std::string toString(EllUpdate v);
std::string toString(InitialGuess v);
std::string toString(Reference v);
std::string toString(SyncDepth v);
std::string toString(UnregisteredColour v);
// Throw std::invalid_argument listing the accepted values.
void fromString(const std::string& s, Engine& v);
void fromString(const std::string& s, EllPolicy& v);
void fromString(const std::string& s, EllUpdate& v);
void fromString(const std::string& s, InitialGuess& v);
void fromString(const std::string& s, Reference& v);
void fromString(const std::string& s, SyncDepth& v);
void fromString(const std::string& s, UnregisteredColour& v);

// visitParams' sections, each with its struct (const or not): visit(section, name, field) for
// every parameter of the section, in the order of the section's fields.
template <typename Selection, typename Visitor>
void visitSelectionParams(Selection& s, Visitor&& visit) {
  visit("selection", "target_points", s.target_points);
  visit("selection", "min_depth", s.min_depth);
  visit("selection", "max_depth", s.max_depth);
  visit("selection", "canny_fallback", s.canny_fallback);
  visit("selection", "scale_with_image", s.scale_with_image);
}

template <typename CoarseToFine, typename Visitor>
void visitCoarseToFineParams(CoarseToFine& c, Visitor&& visit) {
  visit("coarse_to_fine", "ell_init", c.ell_init);
  visit("coarse_to_fine", "ell_min", c.ell_min);
  visit("coarse_to_fine", "ell_reduction", c.ell_reduction);
  visit("coarse_to_fine", "sigma", c.sigma);
  visit("coarse_to_fine", "color_ell", c.color_ell);
  visit("coarse_to_fine", "color_sigma", c.color_sigma);
  visit("coarse_to_fine", "sparsification", c.sparsification);
  visit("coarse_to_fine", "ell_depth_reference", c.ell_depth_reference);
  visit("coarse_to_fine", "depth_noise", c.depth_noise);
  visit("coarse_to_fine", "level_points", c.level_points);
  visit("coarse_to_fine", "level_iterations", c.level_iterations);
  visit("coarse_to_fine", "level_eps", c.level_eps);
  visit("coarse_to_fine", "level_acceleration", c.level_acceleration);
  visit("coarse_to_fine", "photometric", c.photometric);
  visit("coarse_to_fine", "reverse_photometric", c.reverse_photometric);
  visit("coarse_to_fine", "grey_smoothing", c.grey_smoothing);
  visit("coarse_to_fine", "edge_variance", c.edge_variance);
  visit("coarse_to_fine", "tukey_sigmas", c.tukey_sigmas);
  visit("coarse_to_fine", "point_to_plane", c.point_to_plane);
  visit("coarse_to_fine", "dense_point_to_plane", c.dense_point_to_plane);
  visit("coarse_to_fine", "exact_depth_grid_stride", c.exact_depth_grid_stride);
  visit("coarse_to_fine", "depth_led", c.depth_led);
  visit("coarse_to_fine", "photometric_gain", c.photometric_gain);
  visit("coarse_to_fine", "photometric_vignetting", c.photometric_vignetting);
  visit("coarse_to_fine", "exposure_time", c.exposure_time);
  visit("coarse_to_fine", "min_points", c.min_points);
  visit("coarse_to_fine", "covariance_scale", c.covariance_scale);
}

template <typename Paper, typename Visitor>
void visitPaperParams(Paper& a, Visitor&& visit) {
  visit("paper", "ell_policy", a.ell_policy);
  visit("paper", "ell_update", a.ell_update);
  visit("paper", "ell_init", a.ell_init);
  visit("paper", "ell_min", a.ell_min);
  visit("paper", "ell_max", a.ell_max);
  visit("paper", "ell_step", a.ell_step);
  visit("paper", "ell_reduction", a.ell_reduction);
  visit("paper", "sigma", a.sigma);
  visit("paper", "color_ell", a.color_ell);
  visit("paper", "color_sigma", a.color_sigma);
  visit("paper", "sparsification", a.sparsification);
  visit("paper", "eps_transform", a.eps_transform);
  visit("paper", "eps_gradient", a.eps_gradient);
  visit("paper", "min_step", a.min_step);
  visit("paper", "max_step", a.max_step);
  visit("paper", "omega_scale", a.omega_scale);
  visit("paper", "v_scale", a.v_scale);
  visit("paper", "max_iterations", a.max_iterations);
  visit("paper", "carry_ell", a.carry_ell);
  visit("paper", "min_points", a.min_points);
  visit("paper", "hard_ell_reductions", a.hard_ell_reductions);
  visit("paper", "covariance_scale", a.covariance_scale);
}

template <typename Odometry, typename Visitor>
void visitOdometryParams(Odometry& o, Visitor&& visit) {
  visit("odometry", "initial_guess", o.initial_guess);
  visit("odometry", "threads", o.threads);
  visit("odometry", "reference", o.reference);
  visit("odometry", "keyframe_matched_fraction", o.keyframe_matched_fraction);
  visit("odometry", "keyframe_translation", o.keyframe_translation);
  visit("odometry", "keyframe_rotation", o.keyframe_rotation);
  visit("odometry", "window_keyframes", o.window_keyframes);
  visit("odometry", "lost_matched_fraction", o.lost_matched_fraction);
  visit("odometry", "hard_matched_fraction", o.hard_matched_fraction);
  visit("odometry", "max_translation", o.max_translation);
  visit("odometry", "max_rotation", o.max_rotation);
  visit("odometry", "lost_speed", o.lost_speed);
  visit("odometry", "lost_angular_speed", o.lost_angular_speed);
  visit("odometry", "sync_depth", o.sync_depth);
  visit("odometry", "unregistered_colour", o.unregistered_colour);
  visit("odometry", "second_start", o.second_start);
  visit("odometry", "second_start_check", o.second_start_check);
  visit("odometry", "second_start_memory", o.second_start_memory);
  visit("odometry", "turn_start", o.turn_start);
  visit("odometry", "rest_start", o.rest_start);
}

// Calls visit(section, name, field) for every parameter; field is int&, double&, bool& or one
// of the enums above. Sections: "selection", "registration", "coarse_to_fine", "paper",
// "odometry".
template <typename Params_, typename Visitor>
void visitParams(Params_& p, Visitor&& visit) {
  visitSelectionParams(p.selection, visit);
  visit("registration", "engine", p.registration.engine);
  visitCoarseToFineParams(p.coarse_to_fine, visit);
  visitPaperParams(p.paper, visit);
  visitOdometryParams(p.odometry, visit);
}

// The paper's A-CVO as the authors' code runs it (config/paper.yaml; docs/method.md §4 says
// where it follows the code rather than the paper's text), frame to frame.
Params paperParams();
// CVO, the same engine on the fixed length-scale schedule (config/cvo.yaml).
Params cvoParams();

// The minimum cloud size of the engine in use.
int minPoints(const Params& p);

// Every parameter as (section + separator + name, its value as YAML writes it), in visitParams'
// order: what a log shows.
std::vector<std::pair<std::string, std::string>> paramTexts(const Params& p, char separator = '.');
// "section<separator>name=value" for every parameter whose value differs between `from` and
// `to`, separated by spaces (empty when none does).
std::string describeChanges(const Params& from, const Params& to, char separator = '.');

// Empty when the values are consistent; otherwise a message naming the offending parameter.
std::string validate(const Params& p);

// Loads a YAML file with the sections above. Unknown sections or keys, wrong value types and
// inconsistent values throw std::runtime_error naming the file and the key.
Params loadParams(const std::string& path);
// Applies a YAML text on top of `base` (same rules); used by loadParams and by tests.
Params parseParams(const std::string& yaml_text, const Params& base = Params(),
                   const std::string& source_name = "<string>");

}  // namespace acvo
