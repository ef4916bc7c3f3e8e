#include "synth/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "synth/random.hpp"

namespace acvo::synth {
namespace {

constexpr double kReferenceSpeed = 0.3;  // m/s at which the random waves' base frequencies apply
// Bounds on the random motion's offsets from the start over a sequence, per axis of the
// start's camera frame (translation) and per rotation-vector component.
constexpr double kMaxRandomOffset = 0.5;  // m
constexpr double kMaxRandomAngle = 0.5;   // rad (29 deg)
constexpr double kXyzAmplitude = 0.2;     // m
constexpr double kRpyAmplitude = 15.0 * M_PI / 180.0;
constexpr double kCircleRadius = 0.5;   // m
constexpr double kSwaySideways = 0.03;  // m
constexpr double kSwayVertical = 0.02;  // m
constexpr double kSwayPan = 1.5 * M_PI / 180.0;

// Back-and-forth profile on tau in [0, 1]: 0 -> +1 -> -1 -> 0 with zero velocity and
// acceleration at both ends, so consecutive segments (one per axis) join smoothly.
// sin(x) (1 - cos x) / 2 peaks at x = 2 pi / 3 with 3 sqrt(3) / 8; its total variation is 4.
double backAndForth(double tau) {
  const double x = 2.0 * M_PI * tau;
  return std::sin(x) * (1.0 - std::cos(x)) * 0.5 / (3.0 * std::sqrt(3.0) / 8.0);
}

// Segments take the axes x, y, z in turn (also before t = 0, for blur sub-frames).
int axisOfSegment(double segment) {
  const int k = static_cast<int>(std::fmod(segment, 3.0));
  return k < 0 ? k + 3 : k;
}

Eigen::Matrix3d expSo3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

double rotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

}  // namespace

std::optional<MotionKind> parseMotionKind(const std::string& name) {
  if (name == "random") return MotionKind::kRandom;
  if (name == "xyz") return MotionKind::kXyz;
  if (name == "rpy") return MotionKind::kRpy;
  if (name == "circle") return MotionKind::kCircle;
  if (name == "still") return MotionKind::kStill;
  if (name == "sway") return MotionKind::kSway;
  return std::nullopt;
}

std::string toString(MotionKind kind) {
  switch (kind) {
    case MotionKind::kRandom:
      return "random";
    case MotionKind::kXyz:
      return "xyz";
    case MotionKind::kRpy:
      return "rpy";
    case MotionKind::kCircle:
      return "circle";
    case MotionKind::kStill:
      return "still";
    case MotionKind::kSway:
      return "sway";
  }
  return "?";
}

Motion::Motion(const MotionOptions& options) : options_(options) {
  if (options.frames < 0) throw std::invalid_argument("frames must not be negative");
  if (!(options.rate > 0) || !std::isfinite(options.rate))
    throw std::invalid_argument("rate must be positive");
  if (!(options.speed >= 0) || !std::isfinite(options.speed))
    throw std::invalid_argument("speed must be a non-negative number");
  if (options.kind != MotionKind::kRandom) return;

  // Faster motion oscillates faster rather than wider, so the camera stays in the room;
  // slower motion keeps the reference frequencies with smaller amplitudes.
  const double time_scale = std::max(options.speed, kReferenceSpeed) / kReferenceSpeed;
  Rng rng(hashCombine(options.seed, 17));
  const double translation_weight[3] = {1.0, 0.5, 0.7};  // right, down, forward
  const double rotation_weight[3] = {0.6, 1.0, 0.35};    // tilt, pan, roll
  for (int axis = 0; axis < 3; ++axis) {
    for (int k = 0; k < 3; ++k) {
      translation_waves_[axis].push_back({translation_weight[axis] * rng.uniform(0.5, 1.0),
                                          time_scale * rng.uniform(0.15, 0.5),
                                          rng.uniform(0.0, 2.0 * M_PI)});
      rotation_waves_[axis].push_back({rotation_weight[axis] * rng.uniform(0.5, 1.0),
                                       time_scale * rng.uniform(0.25, 0.7),
                                       rng.uniform(0.0, 2.0 * M_PI)});
    }
  }

  if (options.speed == 0.0) {
    translation_gain_ = rotation_gain_ = 0.0;
    return;
  }
  fitGains(options);
}

void Motion::fitGains(const MotionOptions& options) {
  // Gains that give the requested mean speeds over the sequence (at least one frame
  // interval), measured on a fine grid.
  const int intervals = std::max(options.frames - 1, 1);
  const int steps = 8 * intervals;
  const double duration = intervals / options.rate, dt = duration / steps;
  double path = 0.0;
  for (int i = 0; i < steps; ++i)
    path +=
        (sumWaves(translation_waves_, (i + 1) * dt) - sumWaves(translation_waves_, i * dt)).norm();
  translation_gain_ = options.speed * duration / path;
  // The angle of exp(g r(t)) is not exactly linear in g: a few fixed-point rounds settle it.
  const double target_angle = options.speed * kAngularPerLinear * duration;
  for (int round = 0; round < 4; ++round) {
    double angle = 0.0;
    Eigen::Matrix3d previous = Eigen::Matrix3d::Identity();  // r(0) = 0
    for (int i = 1; i <= steps; ++i) {
      const Eigen::Matrix3d current = expSo3(rotation_gain_ * sumWaves(rotation_waves_, i * dt));
      angle += rotationAngle(previous, current);
      previous = current;
    }
    rotation_gain_ *= target_angle / angle;
  }
  // Rarely (unlucky phases, long sequences) the offsets from the start would grow too large:
  // then the motion is scaled down, slower than asked but still in the room.
  double offset = 0.0, angle = 0.0;
  for (int i = 0; i <= steps; ++i) {
    offset = std::max(offset, sumWaves(translation_waves_, i * dt).cwiseAbs().maxCoeff());
    angle = std::max(angle, sumWaves(rotation_waves_, i * dt).cwiseAbs().maxCoeff());
  }
  translation_gain_ = std::min(translation_gain_, kMaxRandomOffset / offset);
  rotation_gain_ = std::min(rotation_gain_, kMaxRandomAngle / angle);
}

Eigen::Vector3d Motion::sumWaves(const std::vector<Wave> (&waves)[3], double t) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int axis = 0; axis < 3; ++axis)
    for (const Wave& w : waves[axis])  // minus the value at t = 0: the motion starts at zero
      sum[axis] +=
          w.amplitude * (std::sin(2.0 * M_PI * w.frequency * t + w.phase) - std::sin(w.phase));
  return sum;
}

Eigen::Isometry3d Motion::poseAt(double t) const {
  switch (options_.kind) {
    case MotionKind::kRandom:
      return randomPose(t);
    case MotionKind::kXyz:
      return xyzPose(t);
    case MotionKind::kRpy:
      return rpyPose(t);
    case MotionKind::kCircle:
      return circlePose(t);
    case MotionKind::kStill:
      return options_.start;
    case MotionKind::kSway:
      return swayPose(t);
  }
  return options_.start;
}

Eigen::Isometry3d Motion::randomPose(double t) const {
  const Eigen::Isometry3d& start = options_.start;
  Eigen::Isometry3d pose = start;
  pose.translation() += start.linear() * (translation_gain_ * sumWaves(translation_waves_, t));
  pose.linear() = start.linear() * expSo3(rotation_gain_ * sumWaves(rotation_waves_, t));
  return pose;
}

Eigen::Isometry3d Motion::xyzPose(double t) const {
  Eigen::Isometry3d pose = options_.start;
  if (options_.speed <= 0.0) return pose;
  // Mean speed over a segment = 4 * amplitude / period.
  const double period = 4.0 * kXyzAmplitude / options_.speed;
  const double segment = std::floor(t / period);
  const int axis = axisOfSegment(segment);
  const double offset = kXyzAmplitude * backAndForth(t / period - segment);
  pose.translation() += pose.linear().col(axis) * offset;
  return pose;
}

Eigen::Isometry3d Motion::rpyPose(double t) const {
  Eigen::Isometry3d pose = options_.start;
  if (options_.speed <= 0.0) return pose;
  const double period = 4.0 * kRpyAmplitude / (options_.speed * kAngularPerLinear);
  const double segment = std::floor(t / period);
  const int axis = axisOfSegment(segment);
  const double angle = kRpyAmplitude * backAndForth(t / period - segment);
  pose.linear() = pose.linear() * Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis));
  return pose;
}

Eigen::Isometry3d Motion::swayPose(double t) const {
  Eigen::Isometry3d pose = options_.start;
  if (options_.speed <= 0.0) return pose;
  const double gain = options_.speed / kReferenceSpeed;
  const Eigen::Vector3d offset(gain * kSwaySideways * std::sin(2.0 * M_PI * 0.4 * t),
                               gain * kSwayVertical * std::sin(2.0 * M_PI * 0.27 * t), 0.0);
  pose.translation() += pose.linear() * offset;
  const double pan = gain * kSwayPan * std::sin(2.0 * M_PI * 0.33 * t);
  pose.linear() = pose.linear() * Eigen::AngleAxisd(pan, Eigen::Vector3d::UnitY()).matrix();
  return pose;
}

Eigen::Isometry3d Motion::circlePose(double t) const {
  const Eigen::Isometry3d& start = options_.start;
  // Horizontal right and forward directions of the start view; the circle's centre is
  // kCircleRadius to the left of the start, so the camera first moves forward.
  Eigen::Vector3d forward = start.linear().col(2);
  forward.z() = 0.0;
  forward.normalize();
  const Eigen::Vector3d right = forward.cross(kWorldUp);
  const Eigen::Vector3d eye0 = start.translation();
  const Eigen::Vector3d centre = eye0 - kCircleRadius * right;
  // The looked-at point: on the start's optical axis, as far as the room centre is.
  const Eigen::Vector3d target = eye0 + start.linear().col(2) * (kLookAtTarget - kStartEye).norm();
  const double phase = options_.speed * t / kCircleRadius;
  const Eigen::Vector3d eye =
      centre + kCircleRadius * (std::cos(phase) * right + std::sin(phase) * forward);
  // lookAt drops any roll of the start pose: carry the start's offset from it along.
  const Eigen::Matrix3d offset = lookAt(eye0, target).linear().transpose() * start.linear();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = lookAt(eye, target).linear() * offset;
  pose.translation() = eye;
  return pose;
}

std::vector<Eigen::Isometry3d> makeTrajectory(const MotionOptions& options) {
  const Motion motion(options);
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(options.frames);
  for (int i = 0; i < options.frames; ++i) poses.push_back(motion.poseAt(i / options.rate));
  return poses;
}

}  // namespace acvo::synth
