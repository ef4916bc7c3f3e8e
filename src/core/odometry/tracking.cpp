// The odometry's judgement of a registration and its keyframe rules (tracking.hpp).
#include "acvo/odometry/tracking.hpp"

#include <cmath>
#include <sstream>

namespace acvo {
namespace {

std::string percent(double fraction) {
  std::ostringstream out;
  out.precision(3);
  out << 100.0 * fraction << "%";
  return out.str();
}

}  // namespace

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

bool failed(SolverStatus status) {
  return status == SolverStatus::kTooFewPoints || status == SolverStatus::kNotFinite;
}

double rotationDeg(const Eigen::Isometry3d& T) {
  return logSE3(T).head<3>().norm() * 180.0 / M_PI;
}

Judgement judgeTracking(const SolverResult& s, const Eigen::Isometry3d& frame_motion,
                        const OdometryParams& params) {
  const double rotation_deg = rotationDeg(frame_motion);
  const double translation = frame_motion.translation().norm();
  if (failed(s.status)) {
    return {Tracking::kLost, "registration failed: " + toString(s.status)};
  }
  if (s.matched_fraction < params.lost_matched_fraction) {
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
  const bool unrelated = !failed(s.status) &&
                         s.matched_fraction < kUnrelatedShare * params.odometry.lost_matched_fraction;
  return lost_in_a_row >= 2 || !unrelated;
}

Eigen::Isometry3d atConstantVelocity(const Eigen::Isometry3d& motion, double measured,
                                     double seconds) {
  return expSE3(logSE3(motion) * (seconds / measured));
}

Eigen::Isometry3d motionPrior(const Eigen::Isometry3d& last, double measured, double interval) {
  if (!(measured > 0.0) || !(interval > 0.0) || kBlackoutShare * measured <= interval) return last;
  return atConstantVelocity(last, measured, interval);
}

Matrix6d frameMotionCovariance(const Eigen::Isometry3d& last, const Matrix6d& last_cov,
                               const Matrix6d& current_cov) {
  const Matrix6d ad = adjointSE3(last.inverse());
  return ad * (current_cov + last_cov) * ad.transpose();
}

}  // namespace acvo
