// SE(3) exponential and logarithm in closed form, double precision, with small-angle series.
// Twists are ordered (omega, v): rotation first, then translation.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace acvo {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

Eigen::Matrix3d hat(const Eigen::Vector3d& w);

// Rodrigues: exp([w]x).
Eigen::Matrix3d expSO3(const Eigen::Vector3d& w);
// Rotation vector of R (angle in [0, pi]); robust near 0 and near pi.
Eigen::Vector3d logSO3(const Eigen::Matrix3d& R);

// exp of the twist xi = (omega, v): R = exp([omega]x), t = V(omega) v. omega = 0 gives exactly t = v.
Eigen::Isometry3d expSE3(const Vector6d& xi);
Vector6d logSE3(const Eigen::Isometry3d& T);

// Adjoint of T for twists (omega, v): Ad(T) xi is the twist xi seen through T, so that
// T exp(xi^) = exp((Ad(T) xi)^) T. Block form [R 0; hat(t) R  R]. A covariance C of a left
// perturbation maps to Ad C Ad^T when the pose is multiplied by T on the left.
Matrix6d adjointSE3(const Eigen::Isometry3d& T);

// Inverse of the left Jacobian of SE(3) at xi: d log(exp(a) exp(xi)) / da at a = 0, so that a
// small left perturbation a of exp(xi) changes its logarithm by J^-1 a. Block form
// [A 0; -A Q A  A], A the inverse of the rotation's left Jacobian and Q the coupling of
// rotation and translation (Barfoot, State Estimation for Robotics, 2017, eq. 7.86).
Matrix6d leftJacobianInverseSE3(const Vector6d& xi);

// Re-orthonormalises the rotation part (guards long chains of products against drift).
Eigen::Isometry3d normalized(const Eigen::Isometry3d& T);

}  // namespace acvo
