// The odometry pipeline (odometry.hpp, docs/method.md §7); what it does about the colour camera
// is in colour_camera.cpp.
#include "acvo/odometry/odometry.hpp"

#include <algorithm>
#include <sstream>

#include <tbb/task_arena.h>

#include "acvo/odometry/depth_timing.hpp"
#include "acvo/timing.hpp"

namespace acvo {

struct Odometry::Arena {
  explicit Arena(int threads) : arena(solverThreads(threads)) {}
  tbb::task_arena arena;
};

// One registration of the current frame to a reference, judged, with its covariance.
struct Odometry::Registration {
  // The cloud registered: the frame's own, or its cloud with the depth moved to the colour's
  // time again at the velocity this registration's coarse levels found (retimedCloud).
  std::shared_ptr<PreparedCloud> moving;
  // The last tracked frame's motion from the reference (T: reference -> last), where the
  // reference is an older keyframe: a transform to the reference is a motion from the last
  // tracked frame once composed with it (frameMotion).
  std::optional<Eigen::Isometry3d> last_from_reference;
  SolverResult solver;
  Judgement judgement;
  Matrix6d covariance = lostCovariance();  // of the motion, when tracked
  std::size_t fixed_points = 0;
  StartOutcome second_start;

  Eigen::Isometry3d frameMotion(const Eigen::Isometry3d& to_reference) const {
    return last_from_reference ? *last_from_reference * to_reference : to_reference;
  }
};

namespace {

// Why a frame gave too few points, from what the selector saw: the message names the fault
// of the input (a blank colour image, a depth image without valid values) rather than the
// solver's status alone.
std::string whyTooFewPoints(const CloudStats& stats, const SelectionParams& p) {
  const int candidates = stats.selection.gradient_pixels + stats.selection.canny_pixels;
  if (candidates == 0) return "no intensity gradient anywhere in the colour image";
  std::ostringstream why;
  why << "no valid depth in [" << p.min_depth << ", " << p.max_depth << "] m at its " << candidates
      << " candidate pixels";
  return why.str();
}

}  // namespace

Odometry::Odometry(const Params& params)
    : params_(params),
      pose_covariance_(originCovariance()),
      second_start_(params.odometry),
      colour_(params.odometry.unregistered_colour),
      arena_(std::make_unique<Arena>(params.odometry.threads)) {
  makeEngine();
  const auto window = std::size_t(std::max(params.odometry.window_keyframes, 0));
  if (window > 2 && params.odometry.reference == Reference::kKeyframe) {
    window_ = std::make_unique<KeyframeWindow>(window, params.odometry, params.odometry.threads);
  }
}
Odometry::~Odometry() = default;
Odometry::Odometry(Odometry&&) noexcept = default;
Odometry& Odometry::operator=(Odometry&&) noexcept = default;

OdometryResult Odometry::process(const Frame& frame,
                                 const std::optional<Eigen::Isometry3d>& motion_guess) {
  if (!colour_.ratio()) {
    OdometryResult r = track(frame, motion_guess);
    lookAtColour(frame, r);
    return r;
  }
  OdometryResult r = track(colour_.prepared(frame), motion_guess);
  r.colour_resampled = true;
  return r;
}

OdometryResult Odometry::track(const Frame& frame,
                               const std::optional<Eigen::Isometry3d>& motion_guess) {
  OdometryResult r;
  r.pose = pose_;
  r.pose_covariance = pose_covariance_;
  r.keyframe_index = keyframe_ ? keyframe_->index : 0;
  if (std::string why = frame.problem(); !why.empty()) {
    r.tracking = Tracking::kBadFrame;
    r.message = why;
    return r;
  }
  // 1. The frame's cloud, its depth at the colour's instant.
  const std::shared_ptr<PreparedCloud> current = buildCloud(frame, r);
  r.frame_index = frames_++;
  if (!keyframe_) {
    start(r, current);
    return r;
  }
  // 2. The motion guess.
  r.interval = frame.stamp - last_->cloud->cloud.stamp;
  GuessFacts facts;
  facts.interval = r.interval;
  facts.stamp = frame.stamp;
  const Eigen::Isometry3d prior = guess(motion_guess, facts);
  // 3. The registration to the keyframe, or to the last tracked frame where that fails.
  Registration reg = registerFrame(r, frame, current, prior, facts);
  takeWindow(r);
  // 4. The pose, the keyframe and what the next frame starts from. A lost frame's motion moves
  // no depth: its cloud is kept as built (it may become the reference).
  if (reg.judgement.tracking == Tracking::kLost) reg.moving = current;
  r.depth_retimed = reg.moving != current;
  if (r.depth_retimed) {
    r.cloud = std::shared_ptr<const LabelledCloud>(reg.moving, &reg.moving->cloud);
    r.moving_points = reg.moving->size();
  }
  if (reg.judgement.tracking == Tracking::kLost) {
    lost(r, reg, frame.stamp);
  } else {
    tracked(r, reg, frame.stamp);
  }
  return r;
}

std::shared_ptr<PreparedCloud> Odometry::buildCloud(const Frame& frame, OdometryResult& r) {
  const auto t0 = Clock::now();
  std::shared_ptr<PreparedCloud> current;
  // Frame to frame, every frame becomes the reference: its search grids are built with it.
  // With keyframes, only when it becomes one (asReference).
  const bool every_frame_a_reference = params_.odometry.reference == Reference::kPreviousFrame;
  const Frame at_colour_time = depthAtColourTime(frame, r);
  arena_->arena.execute([&] {
    LabelledCloud cloud = buildLabelledCloud(at_colour_time, params_.selection, &r.cloud_stats);
    // The motion while the shutter was open.
    if (const double exposure = params_.coarse_to_fine.exposure_time; exposure > 0.0) {
      cloud.blur_motion = motionOver(exposure).value_or(Eigen::Isometry3d::Identity());
    }
    current = engine_->prepare(std::move(cloud), every_frame_a_reference);
  });
  r.ms_cloud = msSince(t0);
  r.moving_points = current->size();
  r.ms_prepare = current->ms_prepare;
  r.cloud = std::shared_ptr<const LabelledCloud>(current, &current->cloud);
  return current;
}

Frame Odometry::depthAtColourTime(const Frame& frame, OdometryResult& r) const {
  const double delay = frame.depth_stamp != 0.0 ? frame.stamp - frame.depth_stamp : 0.0;
  r.depth_delay = delay;
  if (params_.odometry.sync_depth == SyncDepth::kNone || delay == 0.0) return frame;
  // The motion over the delay, as the last frame-to-frame motion says (the colour's stamps
  // measure both); unknown until two frames were tracked.
  const std::optional<Eigen::Isometry3d> moved = motionOver(delay);
  if (!moved) return frame;
  std::optional<cv::Mat> depth = depthMovedBy(frame, *moved, params_.selection.min_depth);
  if (!depth) return frame;
  Frame at_colour_time = frame;
  at_colour_time.depth = std::move(*depth);
  r.depth_synced = true;
  return at_colour_time;
}

Eigen::Isometry3d Odometry::guess(const std::optional<Eigen::Isometry3d>& motion_guess,
                                  GuessFacts& facts) const {
  const bool constant_velocity =
      !motion_guess && params_.odometry.initial_guess == InitialGuess::kConstantVelocity;
  facts.predicted = constant_velocity && lastVelocity() && velocity_changes_.count() > 0;
  facts.velocity_changes = velocity_changes_.moment();
  facts.motion_unknown = constant_velocity && !motion_known_;
  if (motion_guess) return *motion_guess;
  return constant_velocity ? motionPrior(velocity_, velocity_interval_, facts.interval)
                           : Eigen::Isometry3d::Identity();
}

Odometry::Registration Odometry::registerFrame(OdometryResult& r, const Frame& frame,
                                               const std::shared_ptr<PreparedCloud>& current,
                                               const Eigen::Isometry3d& prior,
                                               const GuessFacts& facts) {
  const bool last_is_keyframe = last_->index == keyframe_->index;
  // From the keyframe: where the last tracked frame was, then the prior's motion.
  Registration reg = registerTo(
      *keyframe_, current, last_is_keyframe ? prior : last_->to_keyframe * prior, frame, r, facts);
  r.ms_registration = reg.solver.ms_total;

  // Failed against the keyframe: the last tracked frame, closer in time, may still overlap.
  if (reg.judgement.tracking == Tracking::kLost && !last_is_keyframe &&
      int(current->size()) >= engine_->minPoints()) {
    asReference(r, last_->cloud);
    Registration to_last = registerTo(*last_, current, prior, frame, r, facts);
    r.ms_registration += to_last.solver.ms_total;
    if (to_last.judgement.tracking != Tracking::kLost) {
      newKeyframe(r, *last_);
      last_ = keyframe_;
      reg = std::move(to_last);
      r.fell_back_to_previous = true;
    }
  }
  r.keyframe_index = keyframe_->index;
  r.fixed_points = reg.fixed_points;
  r.solver = reg.solver;
  r.tracking = reg.judgement.tracking;
  r.message = reg.judgement.message;
  if (reg.solver.status == SolverStatus::kTooFewPoints) {
    r.message += int(r.moving_points) < engine_->minPoints()
                     ? ": this frame has " + whyTooFewPoints(r.cloud_stats, params_.selection)
                     : ": the reference frame has too few points";
  }
  return reg;
}

Odometry::Registration Odometry::registerTo(const Tracked& reference,
                                            const std::shared_ptr<PreparedCloud>& current,
                                            const Eigen::Isometry3d& guess, const Frame& frame,
                                            OdometryResult& r, const GuessFacts& facts) {
  Registration reg;
  reg.moving = current;
  reg.fixed_points = reference.cloud->size();
  // The motion limits hold per frame: from the last tracked frame, not from an older keyframe.
  const bool from_last = &reference == &*last_ || last_->index == reference.index;
  if (!from_last) reg.last_from_reference = last_->to_keyframe.inverse();
  SolverResult first;
  arena_->arena.execute([&] { first = alignStaged(reference, reg, frame, guess, r); });
  // Second starts from the guess where the motion missed it (second_start.hpp).
  const StartContext context{*engine_, *reference.cloud, *reg.moving, guess, facts};
  arena_->arena.execute(
      [&] { reg.solver = second_start_.apply(context, std::move(first), reg.second_start); });
  r.second_start = r.second_start || reg.second_start.ran;
  r.second_start_kept = r.second_start_kept || reg.second_start.kept;
  judge(reg);
  return reg;
}

SolverResult Odometry::alignStaged(const Tracked& reference, Registration& reg, const Frame& frame,
                                   const Eigen::Isometry3d& guess, OdometryResult& r) {
  const PreparedCloud& fixed = *reference.cloud;
  const bool retimes = params_.odometry.sync_depth == SyncDepth::kOwnMotion &&
                       r.depth_delay != 0.0 && r.interval > 0.0 && engine_->staged();
  if (!retimes) return engine_->align(fixed, *reg.moving, guess);
  // The depth was moved to the colour's time by the last frame's motion (or not at all); the
  // stages before the finest find this frame's own, and the finest registers the depth moved by
  // that.
  SolverResult coarse = engine_->align(fixed, *reg.moving, guess, AlignStages::kCoarse);
  if (failed(coarse.status)) return coarse;
  const auto t0 = Clock::now();
  const Vector6d velocity = logSE3(reg.frameMotion(coarse.transform)) / r.interval;
  // What the cloud was built with: the last frame-to-frame motion over the delay, or nothing.
  const Eigen::Isometry3d before =
      r.depth_synced ? motionOver(r.depth_delay).value_or(Eigen::Isometry3d::Identity())
                     : Eigen::Isometry3d::Identity();
  if (std::optional<LabelledCloud> again = retimedCloud(
          reg.moving->cloud, frame, before, expSE3(velocity * r.depth_delay), params_.selection)) {
    reg.moving = engine_->prepare(std::move(*again), reg.moving->reference);
    r.ms_cloud += msSince(t0);
  }
  return combinedStages(coarse,
                        engine_->align(fixed, *reg.moving, coarse.transform, AlignStages::kFinest));
}

void Odometry::judge(Registration& reg) const {
  const SolverResult& s = reg.solver;
  reg.judgement = judgeTracking(s, reg.frameMotion(s.transform), params_.odometry);
  if (failed(s.status)) {
    reg.judgement.message += " (" + std::to_string(reg.fixed_points) + " and " +
                             std::to_string(reg.moving->size()) + " points)";
  }
  if (reg.judgement.tracking == Tracking::kLost) return;
  const std::optional<Matrix6d> cov = engine_->covariance(s, reg.moving->size());
  if (!cov) {
    reg.covariance = lostCovariance();
    if (reg.judgement.tracking == Tracking::kOk) {
      reg.judgement = {Tracking::kHard, "motion not constrained in every direction"};
    }
  } else {
    reg.covariance = *cov;
  }
  if (reg.judgement.tracking == Tracking::kHard) reg.covariance *= kHardCovarianceFactor;
}

void Odometry::start(OdometryResult& r, const std::shared_ptr<PreparedCloud>& current) {
  lost_in_a_row_ = 0;
  keyframe_ = last_ = Tracked{asReference(r, current), r.frame_index, pose_, pose_covariance_,
                              Eigen::Isometry3d::Identity()};
  r.tracking = Tracking::kFirstFrame;
  r.keyframe_index = r.frame_index;
  r.new_keyframe = true;
}

void Odometry::tracked(OdometryResult& r, const Registration& reg, double stamp) {
  const Tracked& keyframe = *keyframe_;
  const Eigen::Isometry3d& to_keyframe = reg.solver.transform;
  const bool last_is_keyframe = last_->index == keyframe.index;
  r.motion = last_is_keyframe ? to_keyframe : last_->to_keyframe.inverse() * to_keyframe;
  r.registration_covariance = reg.covariance;
  r.motion_covariance = last_is_keyframe
                            ? reg.covariance
                            : frameMotionCovariance(last_->to_keyframe,
                                                    last_->to_keyframe_covariance, reg.covariance);
  pose_ = normalized(keyframe.pose * to_keyframe);
  pose_covariance_ = keyframe.covariance + rotateCovariance(reg.covariance, keyframe.pose.linear());
  r.pose = pose_;
  r.pose_covariance = pose_covariance_;
  if (r.interval > 0.0) {
    const Vector6d velocity = logSE3(r.motion) / r.interval;
    if (const auto last = lastVelocity()) velocity_changes_.add(velocity - *last);
  }
  velocity_ = r.motion;
  velocity_interval_ = r.interval;
  motion_known_ = true;
  second_start_.tracked(stamp, reg.solver.objective, reg.second_start.pulled);
  lost_in_a_row_ = 0;

  Tracked frame{reg.moving, r.frame_index, pose_, pose_covariance_, to_keyframe, reg.covariance};
  if (params_.odometry.reference == Reference::kPreviousFrame ||
      takesKeyframe(reg.judgement, reg.solver, params_.odometry)) {
    frame.cloud = asReference(r, reg.moving);
    newKeyframe(r, std::move(frame));
    last_ = keyframe_;
    r.new_keyframe = true;
    return;
  }
  last_ = std::move(frame);
}

void Odometry::lost(OdometryResult& r, const Registration& reg, double stamp) {
  // Keep the last good pose; never extrapolate a motion we could not confirm.
  velocity_ = Eigen::Isometry3d::Identity();
  velocity_interval_ = 0.0;
  motion_known_ = false;
  second_start_.forget();
  r.motion = Eigen::Isometry3d::Identity();
  ++lost_in_a_row_;
  r.pose = pose_;
  r.pose_covariance =
      last_->covariance + lostGrowth(stamp - last_->cloud->cloud.stamp, params_.odometry);
  if (replacesReference(reg.solver, reg.moving->size(), keyframe_->cloud->size(), lost_in_a_row_,
                        params_)) {
    // The held pose with what it may be wrong by: the next frames are registered from here.
    pose_covariance_ = r.pose_covariance;
    keyframe_ = last_ = Tracked{asReference(r, reg.moving), r.frame_index, pose_, pose_covariance_,
                                Eigen::Isometry3d::Identity()};
    if (window_) window_->clear();  // nothing links the new reference to the window's keyframes
    r.new_keyframe = true;
  }
}

void Odometry::reset(const Eigen::Isometry3d& pose, const Matrix6d& covariance) {
  pose_ = pose;
  pose_covariance_ = covariance;
  velocity_ = Eigen::Isometry3d::Identity();
  velocity_interval_ = 0.0;
  motion_known_ = false;
  velocity_changes_.reset();
  second_start_.forget();
  keyframe_.reset();
  last_.reset();
  if (window_) window_->clear();
  lost_in_a_row_ = 0;
}

std::optional<double> Odometry::lastTrackedStamp() const {
  if (!last_) return std::nullopt;
  return last_->cloud->cloud.stamp;
}

const LabelledCloud* Odometry::keyframeCloud() const {
  return keyframe_ ? &keyframe_->cloud->cloud : nullptr;
}

std::optional<Vector6d> Odometry::lastVelocity() const {
  if (!(velocity_interval_ > 0.0)) return std::nullopt;
  return logSE3(velocity_) / velocity_interval_;
}

std::optional<Eigen::Isometry3d> Odometry::motionOver(double seconds) const {
  if (!(velocity_interval_ > 0.0)) return std::nullopt;
  return atConstantVelocity(velocity_, velocity_interval_, seconds);
}

SolverResult Odometry::alignInArena(const PreparedCloud& fixed, const PreparedCloud& moving,
                                    const Eigen::Isometry3d& guess, AlignStages stages) const {
  SolverResult s;
  arena_->arena.execute([&] { s = engine_->align(fixed, moving, guess, stages); });
  return s;
}

std::shared_ptr<PreparedCloud> Odometry::asReference(OdometryResult& r,
                                                     const std::shared_ptr<PreparedCloud>& cloud) {
  double ms = 0.0;
  arena_->arena.execute([&] { ms = engine_->prepareReference(*cloud); });
  r.ms_prepare += ms;
  r.ms_cloud += ms;
  return cloud;
}

}  // namespace acvo
