// The odometry pipeline: owns the keyframe and the last tracked frame, builds each cloud once,
// guesses the motion (constant velocity, identity or a guess from outside), registers, composes
// the pose and its covariance, judges tracking, takes keyframes.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "acvo/cloud/colour_depth_check.hpp"
#include "acvo/odometry/covariance.hpp"
#include "acvo/cloud/frame.hpp"
#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/params.hpp"
#include "acvo/registration/engine.hpp"
#include "acvo/math/se3.hpp"
#include "acvo/odometry/velocity_changes.hpp"

namespace acvo {

enum class Tracking { kOk, kHard, kLost, kFirstFrame, kBadFrame };
std::string toString(Tracking t);

struct OdometryResult {
  Tracking tracking = Tracking::kBadFrame;
  std::string message;  // why tracking is hard / lost / the frame is bad; empty when ok
  // Camera pose of this frame in the odometry frame (the first frame's camera, or the pose
  // given to reset()), optical-frame convention. Held (the last tracked pose) when lost.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // Covariance of `pose` (covariance.hpp: rotation first, left perturbation, odometry-frame
  // axes): the keyframe's plus this frame's registration to it; grown by lostGrowth while lost.
  Matrix6d pose_covariance = originCovariance();
  // Motion from this frame's camera to the last tracked frame's camera (T: current -> last),
  // over `interval` seconds: what a velocity is made of. Identity when not tracked.
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  double interval = 0.0;  // s from the last tracked frame to this one (0: first or bad frame)
  // Covariance of this frame's registration (T: current -> keyframe, in the keyframe camera's
  // axes): covariance_scale * (-H)^-1 (scaledInverseInformation), times 10 when tracking is
  // hard; kLostVariance on the diagonal when lost.
  Matrix6d registration_covariance = lostCovariance();
  // Covariance of `motion` (T: current -> last tracked, in the last tracked camera's axes): the
  // registration's when the last tracked frame is the keyframe; otherwise both registrations
  // to the keyframe (this frame's and the last tracked frame's) carried through
  // motion = last_to_keyframe^-1 * to_keyframe (frameMotionCovariance). kLostVariance when not
  // tracked.
  Matrix6d motion_covariance = lostCovariance();
  // Frames are numbered from 0 in the order processed (bad frames get no number).
  std::uint64_t frame_index = 0;
  std::uint64_t keyframe_index = 0;  // the keyframe this frame was registered to
  bool new_keyframe = false;         // this frame is the keyframe from now on
  // Registered to the last tracked frame because the registration to the keyframe failed
  // (that frame became the keyframe).
  bool fell_back_to_previous = false;
  // The registered motion missed the motion guess by more than a hand-held camera's velocity
  // changes in a frame, or by less but unusually for this camera (kSecondStartCheckSigmas), so
  // the finest level was run again from the guess (a second start,
  // OdometryParams::second_start); or no motion was known yet and the points the registration
  // left disagreeing were registered alone (kRestFraction). And whether that result was kept.
  bool second_start = false;
  bool second_start_kept = false;
  std::shared_ptr<const LabelledCloud> cloud;  // this frame's cloud (null for a bad frame)
  SolverResult solver;                         // the registration that decided this frame
  std::size_t fixed_points = 0;                // points of the cloud registered to
  std::size_t moving_points = 0;
  // s from the depth's stamp to the colour's (Frame::depth_stamp; 0 when synchronised), and
  // whether the depth was moved over it (OdometryParams::sync_depth, a velocity known).
  double depth_delay = 0.0;
  bool depth_synced = false;
  // ... and moved (again) by the motion the registration's first stages found for this frame,
  // which matches its colour better than the last frame's motion can.
  bool depth_retimed = false;
  // building this frame's cloud (the depth moved to the colour's time, selection, labels,
  // self-kernel)
  double ms_cloud = 0.0;
  // of which: search grids + self-kernel pairs (a keyframe's grids when it became one)
  double ms_prepare = 0.0;
  double ms_registration = 0.0;  // the solver (both registrations when it fell back)
  CloudStats cloud_stats;
  // The colour check's verdict became known with this frame (Odometry::colourCheck()), and
  // whether this frame's colour was resampled to the depth camera
  // (OdometryParams::resample_unregistered_colour; from the frame after the verdict).
  bool colour_verdict_now = false;
  bool colour_resampled = false;
};

// A registered motion that misses the motion guess by more than this in one frame gets a second
// start (OdometryParams::second_start): a velocity change of 0.6 m/s or 90 deg/s within a frame
// at 30 Hz. The guess missed the registered motion by up to 15 mm and 1.5 deg on teddy200, 20 mm
// and 1.4 deg on kitchen7s_dev, 34 mm on a rendered room at 0.8 m/s (its first frame, whose guess
// knows no velocity yet), 60-140 mm where a person crossing at 1 m/s had pulled the
// registration along. Over a longer interval t the limits grow by (t / kSecondStartInterval)^2,
// as the miss of a camera's own acceleration does (every 4th frame of teddy200 with fixed limits:
// 0.0047 / 0.485 -> 0.0058 / 0.559, the second start kept where the camera's own motion
// changed).
inline constexpr double kSecondStartTranslation = 0.02;  // m
inline constexpr double kSecondStartRotation = 3.0;      // deg
inline constexpr double kSecondStartInterval = 1.0 / 30.0;  // s
// The second start, from the guess, is kept unless the first's kernel value at the finest level
// is more than this times its own: of two maxima of the objective the one the camera's own
// motion predicts, unless the other clearly scores higher. Where a person covers half the view
// the two score alike (measured 17.8 and 17.4, 14.4 and 13.8, the person's mode the higher);
// where the camera itself jerked the second start scores 5-8x lower (the first frames of two
// rendered rooms at 0.6 and 0.8 m/s). 1.1 and 1.3 measured the same as 1.2 (docs/accuracy.md,
// eighteenth round).
inline constexpr double kSecondStartMargin = 1.2;
// A kept second start says that something in view pulls the registration away from the camera's
// own motion: for kSecondStartMemory seconds after a tracked frame that kept one, the first start
// must score kSecondStartKeptMargin times the second's to be kept instead. A person walking at
// 0.5 m/s (acvo_synth --walker 0.5, seed 62) is outscored by the room as it enters and then,
// filling more of the view, outscores it by up to 1.42x: with the plain margin the registration
// followed it for 30 frames, 35 mm a frame off. A camera's own jerk leaves the second start 5-8x
// lower, above this margin. Margins of 1.5-3 and memories of 3-30 frames at 30 Hz measured
// alike; 1 frame did not hold (docs/accuracy.md, twenty-first round). Frames more than the
// memory apart (under 4 Hz) keep the plain margin.
inline constexpr double kSecondStartKeptMargin = 2.0;
inline constexpr double kSecondStartMemory = 0.25;  // s
// Under those limits a registration whose motion misses the guess by more than
// kSecondStartCheckSigmas times the guess's usual miss (the root mean square of the camera's
// recent velocity changes over the interval, VelocityChanges), and by at least
// kSecondStartCheckTranslation or kSecondStartCheckRotation (grown with the interval as the
// limits), gets a second start too; only where the guess is the constant-velocity prediction
// from a known velocity (not an identity guess, nor one given from outside, whose usual miss is
// not measured). There the camera's own acceleration may be the cause, so the guess has no
// precedence: the second start is kept only where it scores kSecondStartCheckMargin times the
// first (within kSecondStartMemory of a kept one, as above: unless the first scores
// kSecondStartKeptMargin times higher). A person walking at 0.5 m/s pulls the registration
// 11-19 mm off as it enters the view, under the limits, while the smooth camera's guess misses
// by about 1 mm (w62's first crossing: 0.0494 -> 0.0026 m/s); a fast hand-held camera's guess
// misses by 2-10 mm a frame, 4-7 mm in root mean square, and its threshold follows (the
// untextured room at 0.8 m/s: 1 second start in 150 frames, as with the limits alone;
// kitchen7s_dev 2 in 50, teddy200 none; none kept).
// With the floors alone (no sigmas) and the plain margin, that room kept second starts that
// scored within 0.1% of the first, on a flat ridge of the objective, and lost its way (0.0019
// -> 0.1377 m/s; docs/accuracy.md, twenty-second round). A pull that was not caught enters the
// velocity changes and raises the threshold for the next ten frames or so.
inline constexpr double kSecondStartCheckTranslation = 0.005;  // m
inline constexpr double kSecondStartCheckRotation = 0.75;      // deg
inline constexpr double kSecondStartCheckSigmas = 3.0;
inline constexpr double kSecondStartCheckMargin = 1.1;
// A turn that misses the guess by more than kSecondStartRotation, registered with a translation
// that misses it by more than kSecondStartTranslation too and with a kernel value under
// kTurnStartScoreShare times the last tracked frame's, may be the turn's own image motion taken
// partly as a sideways move: a small turn and a sideways move shift the image alike, and the
// coarse levels' few points cannot tell them apart. The finest level is then run again from the
// turn registered with the guess's translation, and kept where its kernel value is
// kSecondStartMargin times the first's (docs/accuracy.md, twenty-seventh round: a camera turning
// at 112 deg/s whose turn jumped from 0.7 to 5.3 deg a frame, registered 91 mm off with a kernel
// value of 5.6 against the last frame's 33.4, is kept to 0.02 mm at 4.4x the first's). The low
// score keeps the extra start, and its cost, to frames whose first maximum is in doubt: a
// registration that found the camera's motion scores about as the frames before did, however far
// its guess missed (a frame dropped). Over 56 rendered sets the turn and the translation both
// missed on nine frames besides that one: a person pulling (0.41-0.63 of the last frame's kernel
// value; the second start from the guess is what holds those) or the first registered frame (no
// last value). What misled the first is no pull from something in view: kSecondStartMemory does
// not start (Odometry::turnStart).
inline constexpr double kTurnStartScoreShare = 0.3;

// Where no velocity is known yet (the first registered frame, or the first after a lost one),
// the guess cannot hold the registration to the camera's motion, and something large moving in
// view can take it along from the start (a person crossing 1.2 m in front of a camera at
// 0.4 m/s: every frame 55 mm off until the person left). Where more than kRestFraction of the
// registered points disagree with the reference under the motion found (agreement.hpp), those
// points alone are registered from the guess, and the whole cloud is refined at the finest level
// from their motion: a second start from the rest of the points. It is kept where the image's
// pixels agree with it kRestMargin times as often as with the first (denseAgreement): the
// camera's motion is the one most of the view agrees with, whatever the selection chose. That
// person: 2730 pixels agree with the first start, 3128 with the rest's; 0.1413 -> 0.0013 m/s
// (docs/accuracy.md, twenty-third round). A kept one starts kSecondStartMemory as any kept
// second start does (without: a person at 1 m/s taken again from frame 3 to 8, 11 mm a frame).
inline constexpr double kRestFraction = 0.1;
inline constexpr double kRestMargin = 1.1;

// Tracking judgement of a registration, from the solver's result and the motion it implies
// from the last tracked frame (`frame_motion`; the registration's own transform when the frame
// is registered to the previous one):
//  - lost: the solver failed (too few points, not finite), fewer than lost_matched_fraction of
//    the frame's points found a kernel partner (nothing in common: noise, another view), or the
//    motion exceeds max_translation / max_rotation per frame. A low overlap alone is not lost:
//    a fast motion registered from the part of the view it keeps is kept.
//  - hard: matched below hard_matched_fraction, iteration cap reached, or the engine found it
//    hard (SolverResult::hard: the paper's length-scale kept reaching its upper bound).
//  - ok otherwise.
struct Judgement {
  Tracking tracking = Tracking::kOk;
  std::string message;  // empty when ok
};
Judgement judgeTracking(const SolverResult& s, const Eigen::Isometry3d& frame_motion,
                        const OdometryParams& params);

// Covariance of motion = last^-1 * current (both T: camera -> keyframe camera, each with its
// registration's covariance, left perturbations in the keyframe camera's axes), in the last
// camera's axes: Ad(last^-1) (current_cov + last_cov) Ad(last^-1)^T. The two registrations are
// taken as independent; both were made against the same keyframe cloud, so their errors are
// positively correlated and the sum is an upper bound on what the difference can be off by.
Matrix6d frameMotionCovariance(const Eigen::Isometry3d& last, const Matrix6d& last_cov,
                               const Matrix6d& current_cov);

// The constant-velocity guess for a frame `interval` seconds after the last tracked frame, from
// the last motion, measured over `measured` seconds: that motion scaled down in proportion when
// it spanned clearly more time (< 3/4 of it: a registration across a blackout); never scaled up.
Eigen::Isometry3d motionPrior(const Eigen::Isometry3d& last, double measured, double interval);

// The frame with the depth its registration used (its cloud's): moved to the colour's time where
// the odometry moved it (OdometryResult::depth_synced, depth_retimed), as it came otherwise; the
// frame as given when it has no cloud (a bad frame). What looks at colour and depth together
// (ColourDepthCheck) sees them of one instant, as the odometry did.
Frame depthAsRegistered(const Frame& frame, const OdometryResult& r);

// Whether a frame registered to the keyframe becomes the next keyframe (keyframe reference):
// hard to track, matched below keyframe_matched_fraction, or moved beyond keyframe_translation
// / keyframe_rotation from the keyframe.
bool takesKeyframe(const Judgement& judgement, const SolverResult& s, const OdometryParams& params);

// Whether a lost frame (with `points` points) replaces the keyframe, so that the next frame is
// registered against it. Never a frame with too few points (blank); always when the keyframe
// itself has too few. previous_frame: otherwise yes, except a first lost frame with next to
// nothing in common with the reference (matched below a fifth of lost_matched_fraction: a frame
// of noise, a glitch). keyframe: from the second lost frame in a row (the view has changed for
// good); the first is followed by a try against the last good keyframe.
bool replacesReference(const SolverResult& s, std::size_t points, std::size_t reference_points,
                       int lost_in_a_row, const Params& params);

// Lost and keyframe handling (see the functions above):
//  - previous_frame: every tracked frame is the next frame's reference (the paper's driver).
//  - keyframe: each frame is registered to the keyframe, from the last tracked frame's motion
//    from it composed with the motion prior; when that fails (lost), to the last tracked frame,
//    which then becomes the keyframe. A frame that is lost keeps the last good pose (its
//    covariance grows with lostGrowth) and drops the motion prior.
//  - either: a registration whose motion misses the prior by more than kSecondStartTranslation
//    or kSecondStartRotation is run again at the finest level from the prior, and that second
//    start is kept unless the first's kernel value there is kSecondStartMargin times higher
//    (kSecondStartKeptMargin within kSecondStartMemory of a kept one;
//    OdometryParams::second_start); one that misses it by less, but unusually for the camera
//    (kSecondStartCheckSigmas), is run again too and kept only where the second start scores
//    kSecondStartCheckMargin times higher. One whose turn and translation both miss it by more
//    than the limits, and whose kernel value is under kTurnStartScoreShare times the last
//    frame's, is first run again from its turn with the prior's translation (turnStart). Where no
//    velocity is known yet, a registration that leaves many points unexplained is run again from
//    those points (kRestFraction, kRestMargin).
class Odometry {
 public:
  explicit Odometry(const Params& params = Params());
  ~Odometry();
  Odometry(Odometry&&) noexcept;
  Odometry& operator=(Odometry&&) noexcept;

  // Processes one frame. A frame with a problem (Frame::problem()) is rejected with
  // Tracking::kBadFrame and does not change the state. `motion_guess`, when given, replaces
  // the motion prior: the motion from this frame's camera to the last tracked frame's
  // (T: current -> last, as OdometryResult::motion), e.g. from wheel odometry. Once the colour
  // check has found the colour unregistered, the frame's colour is resampled first
  // (colourResampling); `frame` itself is never changed.
  OdometryResult process(const Frame& frame,
                         const std::optional<Eigen::Isometry3d>& motion_guess = std::nullopt);

  // Drops the keyframe; the next frame starts again from `pose`, known to `covariance`.
  void reset(const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity(),
             const Matrix6d& covariance = originCovariance());

  const Eigen::Isometry3d& pose() const { return pose_; }
  const Matrix6d& poseCovariance() const { return pose_covariance_; }
  const Params& params() const { return params_; }
  // The stamp of the last tracked frame: where a motion guess for the next frame starts.
  std::optional<double> lastTrackedStamp() const;
  // The current keyframe's cloud, if any.
  const LabelledCloud* keyframeCloud() const;
  // Whether depth and colour look registered, from every ColourDepthCheck::kFrameStep-th frame
  // (as registered: depthAsRegistered) until it decides; and the focal ratio each frame's
  // colour is resampled by since (an unregistered verdict, resample_unregistered_colour), if
  // any. Neither changes with reset(): they concern the camera.
  const ColourDepthCheck& colourCheck() const { return colour_check_; }
  std::optional<double> colourResampling() const { return colour_ratio_; }
  // The check's verdict for a log (ColourDepthCheck::describe), and what is done about it.
  std::string describeColour() const;
  // Another camera: the check looks again and the colour is used again until it decides.
  void newCamera();
  // Takes over a check made on this camera (another Odometry's, before a parameter change),
  // and acts on its verdict.
  void takeColourCheck(const ColourDepthCheck& check);

 private:
  // A frame with a known pose, kept as the keyframe or as the last tracked frame.
  struct Tracked {
    std::shared_ptr<PreparedCloud> cloud;
    std::uint64_t index = 0;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();         // camera in the odometry frame
    Matrix6d covariance = Matrix6d::Zero();                         // of pose
    Eigen::Isometry3d to_keyframe = Eigen::Isometry3d::Identity();  // camera -> keyframe camera
    Matrix6d to_keyframe_covariance = Matrix6d::Zero();             // of to_keyframe
  };
  struct Registration;
  // process() but for the colour check.
  OdometryResult track(const Frame& frame, const std::optional<Eigen::Isometry3d>& motion_guess);
  // Gives the frame to the colour check when its turn comes; when the check finds the colour
  // unregistered, resamples it from then on (actOnColourVerdict) and makes this frame the
  // keyframe, its cloud rebuilt from its resampled colour.
  void checkColour(const Frame& frame, OdometryResult& r);
  // The frame with its colour resampled to the depth camera (colour_ratio_ set).
  Frame resampled(const Frame& frame) const;
  // The colour resampling for the check's verdict (resample_unregistered_colour), and the
  // engine without the photometric term, led by the depth, while it lasts.
  void actOnColourVerdict();
  // The steps of track(), in order.
  // The camera's motion over `seconds`, as the last frame-to-frame motion says; none until two
  // frames were tracked.
  std::optional<Eigen::Isometry3d> motionOver(double seconds) const;
  // The last frame-to-frame velocity, a twist per second; none until two frames were tracked.
  std::optional<Vector6d> lastVelocity() const;
  // The frame with its depth moved to the colour's time when they differ (sync_depth).
  Frame depthAtColourTime(const Frame& frame, OdometryResult& r) const;
  // The cloud of the frame at its colour's time.
  std::shared_ptr<PreparedCloud> buildCloud(const Frame& frame, OdometryResult& r);
  // `cloud` with the search grids of a reference built (asReference).
  std::shared_ptr<PreparedCloud> asReferenceCloud(OdometryResult& r,
                                                  const std::shared_ptr<PreparedCloud>& cloud);
  void start(OdometryResult& r, const std::shared_ptr<PreparedCloud>& registered);
  // To the keyframe from the prior, then (lost) to the last tracked frame; fills r's solver
  // figures and judgement.
  Registration registerFrame(OdometryResult& r, const Frame& frame,
                             const std::shared_ptr<PreparedCloud>& current,
                             const Eigen::Isometry3d& prior);
  // Builds the search grids a cloud registered to needs (prepareReference), timed into r.
  void asReference(OdometryResult& r, PreparedCloud& cloud);
  // One registration of the frame's cloud to `reference`. Where the depth is of another
  // instant than the colour (retimes), in two stages with the depth moved again in between.
  Registration registerTo(const Tracked& reference, const std::shared_ptr<PreparedCloud>& current,
                          const Eigen::Isometry3d& guess, const Frame& frame, OdometryResult& r);
  // The second start from the rest of the points, where no motion is known (kRestFraction);
  // returns whether it was kept.
  bool restStart(const Tracked& reference, const Eigen::Isometry3d& guess, Registration& reg,
                 OdometryResult& r);
  // A second start replaces the first: `again`, with the cost of both (addStartCost).
  void keepSecondStart(Registration& reg, OdometryResult& r, SolverResult again);
  // The finest level of reg's frame against `reference` from `start`, as a second start (marked
  // in r, its cost added to reg's: addStartCost); secondStart and turnStart judge the result.
  SolverResult finestFrom(const Tracked& reference, Registration& reg,
                          const Eigen::Isometry3d& start, OdometryResult& r);
  // Where reg's motion missed `guess` (OdometryParams::second_start, kSecondStartTranslation),
  // the finest level again from the guess, kept unless the first scores kSecondStartMargin
  // times higher (kSecondStartKeptMargin within kSecondStartMemory of the last one kept; `stamp`
  // is the frame's); where it missed by less but unusually (kSecondStartCheckSigmas), kept only
  // where it scores kSecondStartCheckMargin times higher than the first.
  void secondStart(const Tracked& reference, const Eigen::Isometry3d& guess, Registration& reg,
                   OdometryResult& r, double stamp);
  // Where reg's turn and translation both missed `guess` by more than the second start's limits
  // (as scaled by secondStart) and it scored low (kTurnStartScoreShare), the finest level again
  // from reg's turn with the guess's translation; returns whether it was kept (kSecondStartMargin
  // times the first's kernel value).
  bool turnStart(const Tracked& reference, const Eigen::Isometry3d& guess, Registration& reg,
                 OdometryResult& r);
  // Whether registrations of this frame move its depth again (sync_depth, a delay, a staged
  // engine).
  bool retimes(const OdometryResult& r) const;
  // The frame's cloud with its depth moved to the colour's time at `velocity` (a twist per
  // second), when that moves a pixel by a tenth or more against what the cloud was built with;
  // null otherwise.
  std::shared_ptr<PreparedCloud> retimedCloud(const PreparedCloud& current, const Frame& frame,
                                              const Vector6d& velocity, OdometryResult& r) const;
  void tracked(OdometryResult& r, const Registration& reg,
               const std::shared_ptr<PreparedCloud>& current);
  void lost(OdometryResult& r, const Registration& reg,
            const std::shared_ptr<PreparedCloud>& current, double stamp);

  Params params_;
  std::unique_ptr<RegistrationEngine> engine_;  // the engine params_ name
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  Matrix6d pose_covariance_;
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  // last frame-to-frame motion
  double velocity_interval_ = 0.0;  // s between the two frames of velocity_ (0: unknown)
  // How the velocity has been changing between tracked frames (the second start's check).
  VelocityChanges velocity_changes_;
  std::optional<Tracked> keyframe_;
  std::optional<Tracked> last_;  // the last tracked frame (the keyframe itself, or after it)
  int lost_in_a_row_ = 0;
  // The stamp of the last tracked frame whose registration kept a second start (none after a
  // lost frame or a reset).
  std::optional<double> second_start_kept_at_;
  // The kernel value of the last tracked frame's registration (none after a lost frame or a
  // reset).
  std::optional<double> last_objective_;
  // Whether this frame's guess is the constant-velocity prediction from a known velocity, with
  // the velocity filter's record of how it missed (the check under the jerk limits needs both).
  bool guess_predicted_ = false;
  // Whether a frame was tracked since the start, the last reset or the last lost frame: until
  // then the constant-velocity guess is the identity, no motion measured.
  bool motion_known_ = false;
  // Whether this frame's guess is the constant-velocity one while no motion is known.
  bool guess_unknown_ = false;
  std::uint64_t frames_ = 0;  // frames numbered so far
  ColourDepthCheck colour_check_;
  // Each frame's colour is resampled by it (colourResampling).
  std::optional<double> colour_ratio_;
  struct Arena;               // the thread pool the solver runs in (odometry.threads)
  std::unique_ptr<Arena> arena_;
};

}  // namespace acvo
