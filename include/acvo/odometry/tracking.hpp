// How the odometry judges a registration and its frames: lost, hard or ok; the keyframe rules;
// the constant-velocity guess; and the covariance of a frame-to-frame motion.
#pragma once

#include <cstddef>
#include <string>

#include <Eigen/Geometry>

#include "acvo/math/se3.hpp"
#include "acvo/params.hpp"
#include "acvo/registration/engine.hpp"

namespace acvo {

enum class Tracking { kOk, kHard, kLost, kFirstFrame, kBadFrame };
std::string toString(Tracking t);

// The solver gave no registration: too few points, or numbers that are not finite.
bool failed(SolverStatus status);

// Tracking judgement of a registration, from the solver's result and the motion it implies from
// the last tracked frame (`frame_motion`; the registration's own transform when the frame is
// registered to the previous one):
//  - lost: the solver failed, fewer than lost_matched_fraction of the frame's points found a
//    kernel partner (nothing in common: noise, another view), or the motion exceeds
//    max_translation / max_rotation per frame. A low overlap alone is not lost: a fast motion
//    registered from the part of the view it keeps is kept.
//  - hard: matched below hard_matched_fraction, iteration cap reached, or the engine found it
//    hard (SolverResult::hard).
//  - ok otherwise.
struct Judgement {
  Tracking tracking = Tracking::kOk;
  std::string message;  // empty when ok
};
Judgement judgeTracking(const SolverResult& s, const Eigen::Isometry3d& frame_motion,
                        const OdometryParams& params);

// Whether a frame registered to the keyframe becomes the next keyframe: hard to track, matched
// below keyframe_matched_fraction, or moved beyond keyframe_translation / keyframe_rotation
// from the keyframe.
bool takesKeyframe(const Judgement& judgement, const SolverResult& s, const OdometryParams& params);

// Whether a lost frame (with `points` points) replaces the keyframe, so that the next frame is
// registered against it. Never a frame with too few points (blank); always when the keyframe
// itself has too few. previous_frame: otherwise yes, except a first lost frame with next to
// nothing in common with the reference (matched below kUnrelatedShare of lost_matched_fraction:
// a frame of noise, a glitch). keyframe: from the second lost frame in a row (the view has
// changed for good); the first is followed by a try against the last good keyframe.
inline constexpr double kUnrelatedShare = 0.2;
bool replacesReference(const SolverResult& s, std::size_t points, std::size_t reference_points,
                       int lost_in_a_row, const Params& params);

// The constant-velocity guess for a frame `interval` seconds after the last tracked frame, from
// the last motion, measured over `measured` seconds: that motion scaled down in proportion when
// it spanned clearly more time (interval under kBlackoutShare of it: a registration across a
// blackout, whose whole motion again would be far off); never scaled up (stamp jitter).
inline constexpr double kBlackoutShare = 0.75;
Eigen::Isometry3d motionPrior(const Eigen::Isometry3d& last, double measured, double interval);

// The camera's motion over `seconds` at the constant velocity of `motion`, measured over
// `measured` seconds.
Eigen::Isometry3d atConstantVelocity(const Eigen::Isometry3d& motion, double measured,
                                     double seconds);

// Covariance of motion = last^-1 * current (both T: camera -> keyframe camera, each with its
// registration's covariance, left perturbations in the keyframe camera's axes), in the last
// camera's axes: Ad(last^-1) (current_cov + last_cov) Ad(last^-1)^T. The two registrations are
// taken as independent; both were made against the same keyframe cloud, so their errors are
// positively correlated and the sum is an upper bound on what the difference can be off by.
Matrix6d frameMotionCovariance(const Eigen::Isometry3d& last, const Matrix6d& last_cov,
                               const Matrix6d& current_cov);

// The rotation angle of a motion, in degrees.
double rotationDeg(const Eigen::Isometry3d& T);

}  // namespace acvo
