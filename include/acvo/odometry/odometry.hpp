// The odometry pipeline: owns the keyframe and the last tracked frame; for each frame builds its
// cloud once (at the colour's instant), guesses the motion, registers the cloud to the keyframe
// (second starts where the motion misses the guess), composes the pose and its covariance,
// judges tracking and takes keyframes. docs/method.md §7.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "acvo/cloud/colour_depth_check.hpp"
#include "acvo/cloud/frame.hpp"
#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/math/se3.hpp"
#include "acvo/odometry/colour_camera.hpp"
#include "acvo/odometry/covariance.hpp"
#include "acvo/odometry/keyframe_window.hpp"
#include "acvo/odometry/second_start.hpp"
#include "acvo/odometry/tracking.hpp"
#include "acvo/odometry/velocity_changes.hpp"
#include "acvo/params.hpp"
#include "acvo/registration/engine.hpp"

namespace acvo {

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
  // axes): the engine's (RegistrationEngine::covariance), times kHardCovarianceFactor when
  // tracking is hard; kLostVariance on the diagonal when lost.
  Matrix6d registration_covariance = lostCovariance();
  // Covariance of `motion` (in the last tracked camera's axes): the registration's when the last
  // tracked frame is the keyframe; otherwise both registrations to the keyframe carried through
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
  // A second start ran (second_start.hpp), and its result was kept.
  bool second_start = false;
  bool second_start_kept = false;
  std::shared_ptr<const LabelledCloud> cloud;  // this frame's cloud (null for a bad frame)
  SolverResult solver;                         // the registration that decided this frame
  std::size_t fixed_points = 0;                // points of the cloud registered to
  std::size_t moving_points = 0;
  // s from the depth's stamp to the colour's (Frame::depth_stamp; 0 when synchronised), and
  // whether the depth was moved to the colour's time by the last frame's motion (sync_depth, a
  // velocity known) and again by the frame's own (depth_timing.hpp).
  double depth_delay = 0.0;
  bool depth_synced = false;
  bool depth_retimed = false;
  // Building this frame's cloud (the depth moved to the colour's time, selection, labels, search
  // structures), of which the search structures (a keyframe's grids when it became one); the
  // solver (both registrations when it fell back).
  double ms_cloud = 0.0;
  double ms_prepare = 0.0;
  double ms_registration = 0.0;
  // The local window (docs/method.md §7.7): its work for the last keyframe, taken up by this
  // frame (the frame after the keyframe, or the one that lost it): the time of the keyframe's
  // registrations to the older keyframes in the window (run alongside this frame's where the
  // engine allows it), its links to older keyframes (the one to the keyframe before included),
  // how far the refinement moved the keyframe's pose from where it was given out (m, deg), and
  // how long this frame waited for that work.
  double ms_window = 0.0;
  int window_links = 0;
  double window_shift = 0.0;
  double window_shift_deg = 0.0;
  double ms_window_wait = 0.0;
  CloudStats cloud_stats;
  // The colour check's verdict became known with this frame (Odometry::colourCheck()), and
  // whether this frame's colour was resampled to the depth camera (from the frame after an
  // unregistered verdict; OdometryParams::unregistered_colour).
  bool colour_verdict_now = false;
  bool colour_resampled = false;
};

// A registration judged hard has its covariance multiplied by this.
inline constexpr double kHardCovarianceFactor = 10.0;

// The frame with the depth its registration used (its cloud's): moved to the colour's time where
// the odometry moved it (OdometryResult::depth_synced, depth_retimed), as it came otherwise; the
// frame as given when it has no cloud (a bad frame). What looks at colour and depth together
// (ColourDepthCheck) sees them of one instant, as the odometry did.
Frame depthAsRegistered(const Frame& frame, const OdometryResult& r);

// Keyframes and lost frames:
//  - keyframe reference: each frame is registered to the keyframe, from the last tracked frame's
//    motion from it composed with the motion guess; when that fails (lost), to the last tracked
//    frame, which then becomes the keyframe. A frame becomes the next keyframe by takesKeyframe.
//  - previous_frame reference: every tracked frame is the next frame's reference (the paper's
//    driver).
//  - a lost frame keeps the last good pose (its covariance grows with lostGrowth), drops the
//    velocity, and replaces the reference by replacesReference.
//  - local window (odometry.window_keyframes, keyframe_window.hpp): a frame that becomes a
//    keyframe is given out at the pose its registration put it; then it is registered to the
//    older keyframes in the window and the window's poses are refined together, while the next
//    frame is registered, which goes on from the keyframe's refined pose. No pose given out
//    changes afterwards.
class Odometry {
 public:
  explicit Odometry(const Params& params = Params());
  ~Odometry();
  Odometry(Odometry&&) noexcept;
  Odometry& operator=(Odometry&&) noexcept;

  // Processes one frame. A frame with a problem (Frame::problem()) is rejected with
  // Tracking::kBadFrame and does not change the state. `motion_guess`, when given, replaces
  // the constant-velocity guess: the motion from this frame's camera to the last tracked frame's
  // (T: current -> last, as OdometryResult::motion), e.g. from wheel odometry. `frame` itself is
  // never changed.
  OdometryResult process(const Frame& frame,
                         const std::optional<Eigen::Isometry3d>& motion_guess = std::nullopt);

  // Drops the keyframe; the next frame starts again from `pose`, known to `covariance`.
  void reset(const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity(),
             const Matrix6d& covariance = originCovariance());

  const Eigen::Isometry3d& pose() const { return pose_; }
  const Matrix6d& poseCovariance() const { return pose_covariance_; }
  const Params& params() const { return params_; }
  // The parameters the registration engine runs with: params(), but where the colour camera
  // changes them (ColourCamera::engineParams).
  Params engineParams() const { return colour_.engineParams(params_); }
  // The stamp of the last tracked frame: where a motion guess for the next frame starts.
  std::optional<double> lastTrackedStamp() const;
  // The current keyframe's cloud, if any.
  const LabelledCloud* keyframeCloud() const;
  // The colour check (ColourCamera) and the focal ratio each frame's colour is resampled by, if
  // any. Neither changes with reset(): they concern the camera.
  const ColourDepthCheck& colourCheck() const { return colour_.check(); }
  std::optional<double> colourResampling() const { return colour_.ratio(); }
  // The check's verdict for a log, what is done about it, and the engine parameters it changed.
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

  // The pipeline's steps, in order.
  OdometryResult track(const Frame& frame, const std::optional<Eigen::Isometry3d>& motion_guess);
  std::shared_ptr<PreparedCloud> buildCloud(const Frame& frame, OdometryResult& r);
  Frame depthAtColourTime(const Frame& frame, OdometryResult& r) const;
  Eigen::Isometry3d guess(const std::optional<Eigen::Isometry3d>& motion_guess,
                          GuessFacts& facts) const;
  Registration registerFrame(OdometryResult& r, const Frame& frame,
                             const std::shared_ptr<PreparedCloud>& current,
                             const Eigen::Isometry3d& prior, const GuessFacts& facts);
  Registration registerTo(const Tracked& reference, const std::shared_ptr<PreparedCloud>& current,
                          const Eigen::Isometry3d& guess, const Frame& frame, OdometryResult& r,
                          const GuessFacts& facts);
  SolverResult alignStaged(const Tracked& reference, Registration& reg, const Frame& frame,
                           const Eigen::Isometry3d& guess, OdometryResult& r);
  void judge(Registration& reg) const;
  void start(OdometryResult& r, const std::shared_ptr<PreparedCloud>& current);
  void tracked(OdometryResult& r, const Registration& reg, double stamp);
  void lost(OdometryResult& r, const Registration& reg, double stamp);
  void lookAtColour(const Frame& frame, OdometryResult& r);
  // `frame`, registered to the current keyframe, becomes the keyframe, and enters the window.
  void newKeyframe(OdometryResult& r, Tracked frame);
  // The window's update of the last keyframe's pose, waited for where its work runs yet.
  void takeWindow(OdometryResult& r);

  // The motion between the two frames of the last velocity over `seconds`, and that velocity as
  // a twist per second; none until two frames were tracked.
  std::optional<Eigen::Isometry3d> motionOver(double seconds) const;
  std::optional<Vector6d> lastVelocity() const;
  // `cloud` with the search structures of a reference built, timed into r.
  std::shared_ptr<PreparedCloud> asReference(OdometryResult& r,
                                             const std::shared_ptr<PreparedCloud>& cloud);
  // One registration in the solver's thread pool.
  SolverResult alignInArena(const PreparedCloud& fixed, const PreparedCloud& moving,
                            const Eigen::Isometry3d& guess, AlignStages stages) const;
  // The engine for the colour camera's verdict (engineParams()).
  void makeEngine();

  Params params_;
  std::shared_ptr<const RegistrationEngine> engine_;  // shared with the window's work
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  Matrix6d pose_covariance_;
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  // last frame-to-frame motion
  double velocity_interval_ = 0.0;    // s between the two frames of velocity_ (0: unknown)
  VelocityChanges velocity_changes_;  // how the velocity has been changing (second starts)
  // Whether a frame was tracked since the start, the last reset or the last lost frame: until
  // then the constant-velocity guess is the identity, no motion measured.
  bool motion_known_ = false;
  SecondStart second_start_;
  std::optional<Tracked> keyframe_;
  std::optional<Tracked> last_;  // the last tracked frame (the keyframe itself, or after it)
  int lost_in_a_row_ = 0;
  std::uint64_t frames_ = 0;  // frames numbered so far
  ColourCamera colour_;
  struct Arena;  // the thread pool the solver runs in (odometry.threads)
  std::unique_ptr<Arena> arena_;
  std::unique_ptr<KeyframeWindow> window_;  // null without a window
};

}  // namespace acvo
