// The odometry pipeline (docs/method.md §7): each frame's cloud, its registration to the
// keyframe, the pose and its covariance, the tracking judgement and the keyframe choice.
#include "acvo/odometry/odometry.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <tbb/task_arena.h>

#include "acvo/odometry/agreement.hpp"
#include "acvo/odometry/covariance.hpp"
#include "acvo/cloud/depth.hpp"
#include "acvo/timing.hpp"

namespace acvo {

struct Odometry::Arena {
  explicit Arena(int threads)
      : arena(threads > 0    ? threads
              : threads == 0 ? int(tbb::task_arena::automatic)
                             : std::max(1, tbb::this_task_arena::max_concurrency() - 1)) {}
  tbb::task_arena arena;
};

// One registration of the current frame to a reference, judged, with its covariance.
struct Odometry::Registration {
  // The cloud registered: the frame's own, or its cloud with the depth moved to the colour's
  // time again at the velocity this registration's coarse levels found (retimedCloud).
  std::shared_ptr<PreparedCloud> moving;
  SolverResult solver;
  Judgement judgement;
  Matrix6d covariance = lostCovariance();  // of the motion, when tracked
  std::size_t fixed_points = 0;
  // A second start's result (restStart's or secondStart's) replaced the first start's.
  bool second_start_kept = false;
};

std::string toString(Tracking t) {
  switch (t) {
    case Tracking::kOk:
      return "ok";
    case Tracking::kHard:
      return "hard";
    case Tracking::kLost:
      return "lost";
    case Tracking::kFirstFrame:
      return "first_frame";
    case Tracking::kBadFrame:
      return "bad_frame";
  }
  return "unknown";
}

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

std::string percent(double fraction) {
  std::ostringstream out;
  out.precision(3);
  out << 100.0 * fraction << "%";
  return out.str();
}

// An upper bound of the image motion `moved` causes, in pixels: its rotation's at the image's
// corner and its translation's at `nearest` metres.
double largestPixelShift(const Eigen::Isometry3d& moved, const Camera& c, double nearest) {
  const double corner2 =
      0.25 * ((c.width / c.fx) * (c.width / c.fx) + (c.height / c.fy) * (c.height / c.fy));
  const double angle = logSO3(moved.linear()).norm();
  return std::max(std::abs(c.fx), std::abs(c.fy)) *
         (angle * (1.0 + corner2) + moved.translation().norm() / std::max(nearest, 0.1));
}

// A depth moved by less than this many pixels is left as it is (TUM fr3's streams are
// synchronised to tens of microseconds).
constexpr double kSyncMinShift = 0.1;

// The camera's motion over `seconds` at the constant velocity of `motion`, measured over
// `measured` seconds.
Eigen::Isometry3d atConstantVelocity(const Eigen::Isometry3d& motion, double measured,
                                     double seconds) {
  return expSE3(logSE3(motion) * (seconds / measured));
}

double rotationDeg(const Eigen::Isometry3d& T) {
  return logSE3(T).head<3>().norm() * 180.0 / M_PI;
}


// A second start's cost added to the first's: the frame's cost is both starts', whichever is kept
// (Odometry::keepSecondStart).
void addStartCost(SolverResult& first, const SolverResult& again) {
  first.ms_total += again.ms_total;
  first.ms_neighbours += again.ms_neighbours;
  first.iterations += again.iterations;
}

// The solver gave no registration: too few points, or numbers that are not finite.
bool failed(SolverStatus status) {
  return status == SolverStatus::kTooFewPoints || status == SolverStatus::kNotFinite;
}
}  // namespace

Frame depthAsRegistered(const Frame& frame, const OdometryResult& r) {
  if (!r.cloud || r.cloud->depth.empty()) return frame;
  Frame out = frame;
  out.depth = r.cloud->depth;
  return out;
}

Judgement judgeTracking(const SolverResult& s, const Eigen::Isometry3d& frame_motion,
                        const OdometryParams& params) {
  const double rotation_deg = rotationDeg(frame_motion);
  const double translation = frame_motion.translation().norm();
  if (failed(s.status)) {
    return {Tracking::kLost, "registration failed: " + toString(s.status)};
  }
  if (s.matched_fraction < params.lost_matched_fraction) {
    // Next to no point found a partner: the solver had nothing to hold on to (a frame of noise,
    // a view with nothing in common). A low overlap alone is not this: a fast motion that
    // keeps a fifth of the view in common is registered from that fifth and kept.
    return {Tracking::kLost, "clouds do not overlap (" + percent(s.matched_fraction) +
                                 " of the points found a partner)"};
  }
  if (translation > params.max_translation || rotation_deg > params.max_rotation) {
    return {Tracking::kLost, "implausible motion (" + std::to_string(translation) + " m, " +
                                 std::to_string(rotation_deg) + " deg in one frame)"};
  }
  if (s.matched_fraction < params.hard_matched_fraction) {
    return {Tracking::kHard,
            "weak overlap (" + percent(s.matched_fraction) + " of the points found a partner)"};
  }
  if (s.status == SolverStatus::kMaxIterations) return {Tracking::kHard, "iteration cap reached"};
  if (!s.hard.empty()) return {Tracking::kHard, s.hard};
  return {Tracking::kOk, ""};
}

Matrix6d frameMotionCovariance(const Eigen::Isometry3d& last, const Matrix6d& last_cov,
                               const Matrix6d& current_cov) {
  const Matrix6d ad = adjointSE3(last.inverse());
  return ad * (current_cov + last_cov) * ad.transpose();
}

Eigen::Isometry3d motionPrior(const Eigen::Isometry3d& last, double measured, double interval) {
  // A registration across a blackout: its whole motion again as the next frame's guess was
  // 0.18 m off and lost that frame. Across a pause of seconds the motion is unknown: one
  // frame's motion is a small guess, that motion times the frames the pause spans could be far
  // off. Stamp jitter (below 4/3 of the interval), or no usable stamps: the last motion as is.
  if (!(measured > 0.0) || !(interval > 0.0) || 0.75 * measured <= interval) return last;
  return atConstantVelocity(last, measured, interval);
}

bool takesKeyframe(const Judgement& judgement, const SolverResult& s,
                   const OdometryParams& params) {
  return judgement.tracking == Tracking::kHard ||
         s.matched_fraction < params.keyframe_matched_fraction ||
         s.transform.translation().norm() > params.keyframe_translation ||
         rotationDeg(s.transform) > params.keyframe_rotation;
}

bool replacesReference(const SolverResult& s, std::size_t points, std::size_t reference_points,
                       int lost_in_a_row, const Params& params) {
  const std::size_t min_points = std::size_t(minPoints(params));
  if (points < min_points) return false;  // a blank frame never replaces the reference
  if (reference_points < min_points) return true;
  if (params.odometry.reference == Reference::kKeyframe) return lost_in_a_row >= 2;
  // Measured (previous_frame): re-seeding from a frame of noise (matched 0) cost the motion of
  // two frames; frames lost narrowly (kitchen7s_dev with the fixed schedule) do re-seed: the
  // next frame registered against the older reference was lost more often (15 frames, not 13).
  const bool unrelated =
      !failed(s.status) && s.matched_fraction < 0.2 * params.odometry.lost_matched_fraction;
  return lost_in_a_row >= 2 || !unrelated;
}

Odometry::Odometry(const Params& params)
    : params_(params),
      engine_(makeRegistrationEngine(params)),
      pose_covariance_(originCovariance()),
      arena_(std::make_unique<Arena>(params.odometry.threads)) {}
Odometry::~Odometry() = default;
Odometry::Odometry(Odometry&&) noexcept = default;
Odometry& Odometry::operator=(Odometry&&) noexcept = default;

void Odometry::reset(const Eigen::Isometry3d& pose, const Matrix6d& covariance) {
  pose_ = pose;
  pose_covariance_ = covariance;
  velocity_ = Eigen::Isometry3d::Identity();
  velocity_interval_ = 0.0;
  motion_known_ = false;
  velocity_changes_.reset();
  keyframe_.reset();
  last_.reset();
  lost_in_a_row_ = 0;
  second_start_kept_at_.reset();
  last_objective_.reset();
}

std::optional<double> Odometry::lastTrackedStamp() const {
  if (!last_) return std::nullopt;
  return last_->cloud->cloud.stamp;
}

const LabelledCloud* Odometry::keyframeCloud() const {
  return keyframe_ ? &keyframe_->cloud->cloud : nullptr;
}

void Odometry::asReference(OdometryResult& r, PreparedCloud& cloud) {
  double ms = 0.0;
  arena_->arena.execute([&] { ms = engine_->prepareReference(cloud); });
  r.ms_prepare += ms;
  r.ms_cloud += ms;
}

Odometry::Registration Odometry::registerTo(const Tracked& reference,
                                            const std::shared_ptr<PreparedCloud>& current,
                                            const Eigen::Isometry3d& guess, const Frame& frame,
                                            OdometryResult& r) {
  Registration reg;
  reg.moving = current;
  reg.fixed_points = reference.cloud->size();
  // The motion limits hold per frame: from the last tracked frame, not from an older keyframe.
  const bool from_last = &reference == &*last_ || last_->index == reference.index;
  auto frameMotion = [&](const Eigen::Isometry3d& to_reference) {
    return from_last ? to_reference : last_->to_keyframe.inverse() * to_reference;
  };
  arena_->arena.execute([&] {
    if (!retimes(r)) {
      reg.solver = engine_->align(*reference.cloud, *current, guess);
      return;
    }
    // The depth was moved to the colour's time by the last frame's motion (or not at all); the
    // stages before the finest find this frame's own, and the finest registers the depth moved
    // by that.
    const SolverResult coarse =
        engine_->align(*reference.cloud, *current, guess, AlignStages::kCoarse);
    if (failed(coarse.status)) {
      reg.solver = coarse;
      return;
    }
    // The velocity over the delay: this frame's own, as the coarse levels found it.
    const Vector6d velocity = logSE3(frameMotion(coarse.transform)) / r.interval;
    if (auto again = retimedCloud(*current, frame, velocity, r)) {
      reg.moving = std::move(again);
    }
    reg.solver = combinedStages(
        coarse, engine_->align(*reference.cloud, *reg.moving, coarse.transform,
                               AlignStages::kFinest));
  });
  // A kept start from the rest of the points has already chosen between two maxima by the
  // image's agreement, which the kernel value secondStart compares cannot tell apart there.
  if (params_.odometry.second_start &&
      !(guess_unknown_ && params_.odometry.rest_start && restStart(reference, guess, reg, r))) {
    secondStart(reference, guess, reg, r, frame.stamp);
  }
  reg.judgement = judgeTracking(reg.solver, frameMotion(reg.solver.transform), params_.odometry);
  const SolverResult& s = reg.solver;
  if (failed(s.status)) {
    reg.judgement.message += " (" + std::to_string(reg.fixed_points) + " and " +
                             std::to_string(reg.moving->size()) + " points)";
  }
  if (reg.judgement.tracking == Tracking::kLost) return reg;

  const std::optional<Matrix6d> cov = engine_->covariance(s, reg.moving->size());
  if (!cov) {
    reg.covariance = lostCovariance();
    if (reg.judgement.tracking == Tracking::kOk) {
      reg.judgement = {Tracking::kHard, "motion not constrained in every direction"};
    }
  } else {
    reg.covariance = *cov;
  }
  if (reg.judgement.tracking == Tracking::kHard) reg.covariance *= 10.0;
  return reg;
}

OdometryResult Odometry::process(const Frame& frame,
                                 const std::optional<Eigen::Isometry3d>& motion_guess) {
  if (!colour_ratio_) {
    OdometryResult r = track(frame, motion_guess);
    checkColour(frame, r);
    return r;
  }
  OdometryResult r = track(resampled(frame), motion_guess);
  r.colour_resampled = true;
  return r;
}

void Odometry::checkColour(const Frame& frame, OdometryResult& r) {
  if (colour_check_.decided() || r.tracking == Tracking::kBadFrame ||
      r.frame_index % ColourDepthCheck::kFrameStep != 0) {
    return;
  }
  colour_check_.add(depthAsRegistered(frame, r));
  if (!colour_check_.decided()) return;
  r.colour_verdict_now = true;
  actOnColourVerdict();
  if (!colour_ratio_ || !last_ || last_->index != r.frame_index) return;
  // This frame becomes the keyframe, its cloud built again from its colour resampled: the next
  // frame, resampled, registered to a keyframe of colour as it came would pair each texture
  // with where it was not (measured: 59 mm off on such a frame of a rendered room).
  OdometryResult again;
  const std::shared_ptr<PreparedCloud> cloud =
      asReferenceCloud(again, buildCloud(resampled(frame), again));
  Tracked rebuilt = *last_;
  rebuilt.cloud = cloud;
  rebuilt.to_keyframe = Eigen::Isometry3d::Identity();
  rebuilt.to_keyframe_covariance = Matrix6d::Zero();
  keyframe_ = last_ = rebuilt;
  r.new_keyframe = true;
  r.ms_cloud += again.ms_cloud;
  r.ms_prepare += again.ms_prepare;
}

Frame Odometry::resampled(const Frame& frame) const {
  return withColourResampled(frame, *colour_ratio_);
}

void Odometry::actOnColourVerdict() {
  const ColourDepthCheck::Verdict& v = colour_check_.verdict();
  const bool had = colour_ratio_.has_value();
  colour_ratio_.reset();
  const UnregisteredColour act = params_.odometry.unregistered_colour;
  if (v.state == ColourDepthCheck::State::kUnregistered && act != UnregisteredColour::kAsGiven) {
    colour_ratio_ = v.best_ratio;
  }
  if (had == colour_ratio_.has_value()) return;
  // Resampled by the focal ratio, a point's colour is still off by the cameras' baseline (a few
  // pixels): near enough for the labels and the selection, too far for grey values compared at
  // a sub-pixel (docs/accuracy.md, fourteenth round). Without the grey values,
  // nothing corrects the kernel's pull towards no motion on real depth: the last level is led
  // by the depth's plane terms (CoarseToFineParams::depth_led; twenty-ninth round). A keyframe
  // prepared by the other engine serves either (the dense term waits for a keyframe with a depth
  // grid); the verdict's frame is rebuilt as the keyframe by the new one (checkColour).
  Params engine_params = params_;
  if (colour_ratio_ && act == UnregisteredColour::kResampleDepthLed) {
    engine_params.coarse_to_fine.photometric = false;
    engine_params.coarse_to_fine.depth_led = true;
  }
  engine_ = makeRegistrationEngine(engine_params);
}

void Odometry::takeColourCheck(const ColourDepthCheck& check) {
  colour_check_ = check;
  actOnColourVerdict();
}

std::string Odometry::describeColour() const {
  std::string text = colour_check_.describe();
  if (colour_ratio_) {
    text += params_.odometry.unregistered_colour == UnregisteredColour::kResampleDepthLed
                ? ". Meanwhile each frame's colour is resampled by that ratio, and registered "
                  "without the photometric term, led by the depth "
                  "(odometry/unregistered_colour: resample_depth_led)"
                : ". Meanwhile each frame's colour is resampled by that ratio "
                  "(odometry/unregistered_colour: resample)";
  }
  return text;
}

void Odometry::newCamera() { takeColourCheck(ColourDepthCheck()); }

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
  const std::shared_ptr<PreparedCloud> current = buildCloud(frame, r);
  r.frame_index = frames_++;
  if (!keyframe_) {
    start(r, current);
    return r;
  }
  r.interval = frame.stamp - last_->cloud->cloud.stamp;
  const bool constant_velocity =
      !motion_guess && params_.odometry.initial_guess == InitialGuess::kConstantVelocity;
  const Eigen::Isometry3d prior =
      motion_guess        ? *motion_guess
      : constant_velocity ? motionPrior(velocity_, velocity_interval_, r.interval)
                          : Eigen::Isometry3d::Identity();
  guess_predicted_ = constant_velocity && lastVelocity() && velocity_changes_.count() > 0;
  guess_unknown_ = constant_velocity && !motion_known_;
  Registration reg = registerFrame(r, frame, current, prior);
  // A lost frame's motion moves no depth: its cloud is kept as built (it may become the
  // reference).
  if (reg.judgement.tracking == Tracking::kLost) reg.moving = current;
  r.depth_retimed = reg.moving != current;
  if (r.depth_retimed) {
    r.cloud = std::shared_ptr<const LabelledCloud>(reg.moving, &reg.moving->cloud);
    r.moving_points = reg.moving->size();
  }
  if (reg.judgement.tracking == Tracking::kLost) {
    lost(r, reg, reg.moving, frame.stamp);
    second_start_kept_at_.reset();
    last_objective_.reset();
  } else {
    tracked(r, reg, reg.moving);
    if (reg.second_start_kept) second_start_kept_at_ = frame.stamp;
  }
  return r;
}

std::optional<Vector6d> Odometry::lastVelocity() const {
  if (!(velocity_interval_ > 0.0)) return std::nullopt;
  return logSE3(velocity_) / velocity_interval_;
}

std::optional<Eigen::Isometry3d> Odometry::motionOver(double seconds) const {
  if (!(velocity_interval_ > 0.0)) return std::nullopt;
  return atConstantVelocity(velocity_, velocity_interval_, seconds);
}

Frame Odometry::depthAtColourTime(const Frame& frame, OdometryResult& r) const {
  const double delay = frame.depth_stamp != 0.0 ? frame.stamp - frame.depth_stamp : 0.0;
  r.depth_delay = delay;
  // The motion over the delay, as the last frame-to-frame motion says (the colour's stamps
  // measure both); unknown until two frames were tracked.
  if (params_.odometry.sync_depth == SyncDepth::kNone || delay == 0.0) return frame;
  const std::optional<Eigen::Isometry3d> moved = motionOver(delay);
  if (!moved ||
      largestPixelShift(*moved, frame.camera, params_.selection.min_depth) < kSyncMinShift) {
    return frame;
  }
  Frame at_colour_time = frame;
  at_colour_time.depth = depthSeenFrom(frame.depth, frame.camera, *moved);
  r.depth_synced = true;
  return at_colour_time;
}

bool Odometry::retimes(const OdometryResult& r) const {
  return params_.odometry.sync_depth == SyncDepth::kOwnMotion && r.depth_delay != 0.0 &&
         r.interval > 0.0 &&
         engine_->staged();
}

std::shared_ptr<PreparedCloud> Odometry::retimedCloud(const PreparedCloud& current,
                                                      const Frame& frame,
                                                      const Vector6d& velocity,
                                                      OdometryResult& r) const {
  const auto t0 = Clock::now();
  // What the cloud was built with: the last frame-to-frame motion over the delay, or nothing.
  const Eigen::Isometry3d before =
      r.depth_synced ? motionOver(r.depth_delay).value_or(Eigen::Isometry3d::Identity())
                     : Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d moved = expSE3(velocity * r.depth_delay);
  if (largestPixelShift(before.inverse() * moved, frame.camera, params_.selection.min_depth) <
      kSyncMinShift) {
    return nullptr;
  }
  // The pixels stay those selected: the colour image has not changed, only where the depth
  // puts their points.
  LabelledCloud cloud =
      withDepth(current.cloud, depthSeenFrom(frame.depth, frame.camera, moved), params_.selection);
  auto out = engine_->prepare(std::move(cloud), current.reference);
  r.ms_cloud += msSince(t0);
  return out;
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

std::shared_ptr<PreparedCloud> Odometry::asReferenceCloud(
    OdometryResult& r, const std::shared_ptr<PreparedCloud>& cloud) {
  asReference(r, *cloud);
  return cloud;
}

void Odometry::start(OdometryResult& r, const std::shared_ptr<PreparedCloud>& registered) {
  lost_in_a_row_ = 0;
  const std::shared_ptr<PreparedCloud> current = asReferenceCloud(r, registered);
  keyframe_ = last_ =
      Tracked{current, r.frame_index, pose_, pose_covariance_, Eigen::Isometry3d::Identity()};
  r.tracking = Tracking::kFirstFrame;
  r.keyframe_index = r.frame_index;
  r.new_keyframe = true;
}

bool Odometry::restStart(const Tracked& reference, const Eigen::Isometry3d& guess,
                         Registration& reg, OdometryResult& r) {
  if (failed(reg.solver.status)) return false;
  const auto t0 = Clock::now();
  const LabelledCloud& fixed = reference.cloud->cloud;
  const LabelledCloud& moving = reg.moving->cloud;
  LabelledCloud rest = disagreeingPoints(fixed, moving, reg.solver.transform);
  if (!(double(rest.size()) > kRestFraction * double(moving.size())) ||
      int(rest.size()) < engine_->minPoints()) {
    return false;
  }
  r.second_start = true;
  SolverResult again;
  arena_->arena.execute([&] {
    const std::shared_ptr<PreparedCloud> alone = engine_->prepare(std::move(rest), false);
    const SolverResult theirs = engine_->align(*reference.cloud, *alone, guess);
    if (failed(theirs.status)) {
      again = theirs;
      return;
    }
    again = combinedStages(theirs, engine_->align(*reference.cloud, *reg.moving,
                                                  theirs.transform, AlignStages::kFinest));
  });
  const bool keep = !failed(again.status) &&
                    denseAgreement(fixed, moving, again.transform) >
                        kRestMargin * denseAgreement(fixed, moving, reg.solver.transform);
  // The registrations' own times, and the sorting, preparing and counting around them.
  again.ms_total = std::max(again.ms_total, msSince(t0));
  addStartCost(reg.solver, again);
  if (!keep) return false;
  keepSecondStart(reg, r, std::move(again));
  return true;
}

void Odometry::keepSecondStart(Registration& reg, OdometryResult& r, SolverResult again) {
  r.second_start_kept = true;
  reg.second_start_kept = true;
  again.iterations = reg.solver.iterations;
  again.ms_total = reg.solver.ms_total;
  again.ms_neighbours = reg.solver.ms_neighbours;
  reg.solver = std::move(again);
}

SolverResult Odometry::finestFrom(const Tracked& reference, Registration& reg,
                                  const Eigen::Isometry3d& start, OdometryResult& r) {
  r.second_start = true;
  SolverResult again;
  arena_->arena.execute(
      [&] { again = engine_->align(*reference.cloud, *reg.moving, start, AlignStages::kFinest); });
  addStartCost(reg.solver, again);
  return again;
}

bool Odometry::turnStart(const Tracked& reference, const Eigen::Isometry3d& guess,
                         Registration& reg, OdometryResult& r) {
  Eigen::Isometry3d start = reg.solver.transform;
  start.translation() = guess.translation();
  SolverResult again = finestFrom(reference, reg, start, r);
  if (failed(again.status) || !(again.objective > kSecondStartMargin * reg.solver.objective)) {
    return false;
  }
  keepSecondStart(reg, r, std::move(again));
  // Kept for the image's ambiguity, not for a pull: no memory of it (kSecondStartMemory).
  reg.second_start_kept = false;
  return true;
}

void Odometry::secondStart(const Tracked& reference, const Eigen::Isometry3d& guess,
                           Registration& reg, OdometryResult& r, double stamp) {
  if (failed(reg.solver.status)) return;
  // Both transforms map into the reference: guess^-1 T is the registered frame motion against
  // the guessed one, from any reference.
  const Eigen::Isometry3d missed = guess.inverse() * reg.solver.transform;
  const double miss_m = missed.translation().norm(), miss_deg = rotationDeg(missed);
  // A velocity change misses by its acceleration times the interval squared.
  const double frames = r.interval / kSecondStartInterval;
  const double scale = std::max(1.0, frames * frames);
  const bool moved_off = miss_m > scale * kSecondStartTranslation;
  const bool turned_off = miss_deg > scale * kSecondStartRotation;
  const bool jerk = moved_off || turned_off;
  // A low kernel value against the last frame's says the first start ended in a wrong maximum.
  const bool scored_low =
      last_objective_ && reg.solver.objective < kTurnStartScoreShare * *last_objective_;
  if (params_.odometry.turn_start && moved_off && turned_off && scored_low &&
      turnStart(reference, guess, reg, r)) {
    return;
  }
  if (!jerk) {
    // The guess's usual miss, where the guess is a constant-velocity prediction: the camera's
    // velocity changes between the last tracked frames (their running second moment; twists,
    // rotation first) over this interval. An identity guess or one given from outside has no
    // such measure. The sigmas grow with the interval, the floors with its square (a frame
    // dropped: the guess misses by the velocity times the interval's excess).
    if (!params_.odometry.second_start_check || !guess_predicted_) return;
    const Matrix6d& change = velocity_changes_.moment();
    const double usual_m = std::sqrt(change.block<3, 3>(3, 3).trace()) * r.interval;
    const double usual_deg =
        std::sqrt(change.block<3, 3>(0, 0).trace()) * r.interval * 180.0 / M_PI;
    const double check_m =
        std::max(scale * kSecondStartCheckTranslation, kSecondStartCheckSigmas * usual_m);
    const double check_deg =
        std::max(scale * kSecondStartCheckRotation, kSecondStartCheckSigmas * usual_deg);
    if (miss_m <= check_m && miss_deg <= check_deg) return;
  }
  SolverResult again = finestFrom(reference, reg, guess, r);
  if (failed(again.status)) return;
  const bool pulled_lately = params_.odometry.second_start_memory && second_start_kept_at_ &&
                             stamp >= *second_start_kept_at_ &&
                             stamp - *second_start_kept_at_ <= kSecondStartMemory;
  if (jerk || pulled_lately) {
    // Beyond what the camera's own acceleration does, or soon after something pulled: the
    // guess's maximum, unless the other clearly scores higher.
    const double margin = pulled_lately ? kSecondStartKeptMargin : kSecondStartMargin;
    if (!(margin * again.objective > reg.solver.objective)) return;
  } else if (!(again.objective > kSecondStartCheckMargin * reg.solver.objective)) {
    // Within it: the guess has no precedence and must clearly score higher.
    return;
  }
  keepSecondStart(reg, r, std::move(again));
}

Odometry::Registration Odometry::registerFrame(OdometryResult& r, const Frame& frame,
                                               const std::shared_ptr<PreparedCloud>& current,
                                               const Eigen::Isometry3d& prior) {
  const bool last_is_keyframe = last_->index == keyframe_->index;
  // From the keyframe: where the last tracked frame was, then the prior's motion.
  Registration reg = registerTo(*keyframe_, current,
                                last_is_keyframe ? prior : last_->to_keyframe * prior, frame, r);
  r.ms_registration = reg.solver.ms_total;

  // Failed against the keyframe: the last tracked frame, closer in time, may still overlap.
  if (reg.judgement.tracking == Tracking::kLost && !last_is_keyframe &&
      int(current->size()) >= engine_->minPoints()) {
    asReference(r, *last_->cloud);
    Registration to_last = registerTo(*last_, current, prior, frame, r);
    r.ms_registration += to_last.solver.ms_total;
    if (to_last.judgement.tracking != Tracking::kLost) {
      keyframe_ = last_;
      keyframe_->to_keyframe = last_->to_keyframe = Eigen::Isometry3d::Identity();
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

void Odometry::tracked(OdometryResult& r, const Registration& reg,
                       const std::shared_ptr<PreparedCloud>& current) {
  const Tracked& keyframe = *keyframe_;
  const Eigen::Isometry3d& to_keyframe = reg.solver.transform;
  const bool last_is_keyframe = last_->index == keyframe.index;
  r.motion = last_is_keyframe ? to_keyframe : last_->to_keyframe.inverse() * to_keyframe;
  r.registration_covariance = reg.covariance;
  r.motion_covariance =
      last_is_keyframe ? reg.covariance
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
  last_objective_ = reg.solver.objective;
  lost_in_a_row_ = 0;

  Tracked frame{current, r.frame_index, pose_, pose_covariance_, to_keyframe, reg.covariance};
  if (params_.odometry.reference == Reference::kPreviousFrame ||
      takesKeyframe(reg.judgement, reg.solver, params_.odometry)) {
    frame.to_keyframe = Eigen::Isometry3d::Identity();
    frame.to_keyframe_covariance = Matrix6d::Zero();
    frame.cloud = asReferenceCloud(r, current);
    keyframe_ = frame;
    r.new_keyframe = true;
  }
  last_ = std::move(frame);
}

void Odometry::lost(OdometryResult& r, const Registration& reg,
                    const std::shared_ptr<PreparedCloud>& current, double stamp) {
  // Keep the last good pose; never extrapolate a motion we could not confirm.
  velocity_ = Eigen::Isometry3d::Identity();
  velocity_interval_ = 0.0;
  motion_known_ = false;
  r.motion = Eigen::Isometry3d::Identity();
  ++lost_in_a_row_;
  r.pose = pose_;
  r.pose_covariance =
      last_->covariance + lostGrowth(stamp - last_->cloud->cloud.stamp, params_.odometry);
  if (replacesReference(reg.solver, current->size(), keyframe_->cloud->size(), lost_in_a_row_,
                        params_)) {
    // The held pose with what it may be wrong by: the next frames are registered from here.
    pose_covariance_ = r.pose_covariance;
    keyframe_ = last_ = Tracked{asReferenceCloud(r, current), r.frame_index, pose_,
                                pose_covariance_, Eigen::Isometry3d::Identity()};
    r.new_keyframe = true;
  }
}

}  // namespace acvo
