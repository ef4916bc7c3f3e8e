// Covariances of motions and poses (6x6, rotation first: a left perturbation exp(xi^) T with
// xi = (rotation x y z, translation x y z); rad^2 and m^2).
//
// A registration's covariance is a scaled inverse of the objective's curvature at the optimum
// (motionCovariance). A pose's covariance is its keyframe's plus the registration's to it,
// rotated into the odometry frame's axes: a random walk over keyframes, not frames, that
// ignores the correlation between a rotation error and the translation after it (the lever
// arm). While tracking is lost the held pose's covariance grows with the time the camera may
// have moved unseen (lostGrowth).
#pragma once

#include <optional>

#include <Eigen/Core>

#include "acvo/params.hpp"
#include "acvo/math/se3.hpp"

namespace acvo {

// Variance (m^2 and rad^2) that tells consumers "do not trust this".
constexpr double kLostVariance = 1e6;
// Diagonal of the pose covariance right after a (re)start: the origin is known exactly, the
// floor only keeps the matrix invertible for consumers that invert it.
constexpr double kOriginVariance = 1e-9;

inline Matrix6d originCovariance() {
  return Matrix6d::Identity() * kOriginVariance;
}
inline Matrix6d lostCovariance() {
  return Matrix6d::Identity() * kLostVariance;
}

// Expresses a covariance given in frame B in frame A's axes; `a_from_b` rotates B into A.
// Works for either block order, since both 3x3 blocks are rotated alike.
Matrix6d rotateCovariance(const Matrix6d& c, const Eigen::Matrix3d& a_from_b);

// Symmetrised copy; a matrix with a non-finite entry or a negative diagonal becomes
// lostCovariance() (nothing can be said of the motion).
Matrix6d sanitiseCovariance(const Matrix6d& c);

// covariance_scale * info^-1 for the information `info` of a registration (the negative of its
// curvature at the optimum; each engine scales it its own way, RegistrationEngine::covariance).
// nullopt when info does not constrain every direction (an eigenvalue below 1e-12 of the
// largest) or the result is not finite.
std::optional<Matrix6d> scaledInverseInformation(const Matrix6d& info, double covariance_scale);

// What the covariance of a held pose gains while the camera is unseen for `seconds`:
// (lost_angular_speed t)^2 on the rotation diagonal, (lost_speed t)^2 on the translation's.
Matrix6d lostGrowth(double seconds, const OdometryParams& params);

}  // namespace acvo
