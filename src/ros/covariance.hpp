// The covariance model of the published odometry (documented in docs/ros.md).
//
// The engine gives, per frame, the covariance of the relative motion (left perturbation,
// rotation first, expressed in the previous camera's frame; a scaled inverse of the objective's
// curvature at the optimum, inflated when tracking is hard). The published pose covariance is
// the sum of these relative covariances, each rotated into the odometry frame's axes by the
// previous camera's orientation: a random walk that ignores the correlation between rotation
// error and later translation (the lever arm), so it grows linearly with the number of frames.
// The twist covariance is the relative covariance divided by dt^2. A lost frame adds
// kLostVariance to every diagonal entry of the pose covariance (its motion is unknown, so is
// every pose after it until a reset), and its twist gets kLostVariance alone.
#pragma once

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace acvo_ros {

using Covariance6 = Eigen::Matrix<double, 6, 6>;

// Variance (m^2 and rad^2) that tells consumers "do not trust this".
constexpr double kLostVariance = 1e6;
// Diagonal of the pose covariance right after a (re)start: the origin is known exactly, the
// floor only keeps the matrix invertible for consumers that invert it.
constexpr double kOriginVariance = 1e-9;

Covariance6 originCovariance();
Covariance6 lostCovariance();

// Engine order (rotation x y z, translation x y z) -> ROS order (x y z, roll pitch yaw).
Covariance6 toRosOrder(const Covariance6& rotation_first);

// Expresses a covariance given in frame B in frame A's axes; `a_from_b` rotates B into A.
// Works for either order, since both 3x3 blocks are rotated alike.
Covariance6 rotate(const Covariance6& c, const Eigen::Matrix3d& a_from_b);

// Symmetrised copy; a matrix with a non-finite entry or a negative diagonal becomes
// lostCovariance() (the engine could not say how good the motion is).
Covariance6 sanitise(const Covariance6& c);

// One step of the model: pose covariance after a frame whose relative-motion covariance is
// `relative` (ROS order, in the frame the motion starts from), that frame's orientation in the
// odometry frame being `odom_from_frame`.
Covariance6 accumulate(const Covariance6& pose, const Covariance6& relative,
                       const Eigen::Matrix3d& odom_from_frame);

// Row-major copy for the 36-element arrays of geometry_msgs.
std::array<double, 36> toArray(const Covariance6& c);

}  // namespace acvo_ros
