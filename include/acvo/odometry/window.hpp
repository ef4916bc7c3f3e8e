// A local window of keyframes (docs/method.md §7.7): the poses of the last few keyframes refined
// together over the registrations that link them, the oldest held fixed.
//
// Each link is one registration of a keyframe's cloud (moving) to an older one's (fixed). Its
// kernel objective F(T), T: moving -> fixed, has its maximum at the registered transform and
// there the curvature H the engine reports; to second order, F(exp(d) T_hat) = F* + d^T H d / 2.
// The window maximises the sum of its links' objectives over the poses, i.e. minimises
//   cost = 1/2 sum_links r^T Lambda r,   r = log(T_fixed^-1 T_moving T_hat^-1),   Lambda = -H,
// or, for a link to a keyframe older than the one before, only its centre's part
// (centreInformation).
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "acvo/math/se3.hpp"

namespace acvo {

// One link between two keyframes, named by Key: the odometry keeps them by frame index, the
// window's math by position among its poses.
template <typename Key>
struct LinkBetween {
  Key fixed{};
  Key moving{};
  // The registration's transform (T: moving -> fixed) and its information (-H, the inverse of
  // the registration's covariance).
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
  Matrix6d information = Matrix6d::Zero();
};
using WindowLink = LinkBetween<int>;

// The information of a link that says where the moving keyframe's centre lies in the fixed
// one's frame and nothing of its rotation: the registration's covariance (of a left perturbation
// of `measured`, as the engine gives it) moved to a right perturbation, d_right = Ad(T_hat^-1)
// d_left, whose translation is the centre's displacement in the moving keyframe's axes and is
// not moved by a rotation about that centre; the inverse of that translation's covariance (its
// marginal: the rotation is left free, not held known); back in r's coordinates,
//   Lambda = Ad(T_hat^-1)^T diag(0, Sigma_vv^-1) Ad(T_hat^-1).
// nullopt where that covariance is not positive definite.
std::optional<Matrix6d> centreInformation(const Matrix6d& covariance,
                                          const Eigen::Isometry3d& measured);

// r of one link at the given poses (camera -> odometry frame).
Vector6d linkResidual(const std::vector<Eigen::Isometry3d>& poses, const WindowLink& link);

// The window's cost at the given poses.
double windowCost(const std::vector<Eigen::Isometry3d>& poses,
                  const std::vector<WindowLink>& links);

// d cost / d e_k for a left perturbation exp(e_k) T_k of each pose, six entries per pose in
// the poses' order (the fixed one's included).
Eigen::VectorXd windowGradient(const std::vector<Eigen::Isometry3d>& poses,
                               const std::vector<WindowLink>& links);

// Gauss-Newton on every pose but the first `held`, which stay as they are, until a step moves
// no pose by more than 1e-9 (rad or m) or after max_iterations; returns the iterations run. A
// pose no link reaches keeps its value.
int refineWindow(std::vector<Eigen::Isometry3d>& poses, const std::vector<WindowLink>& links,
                 int held = 1, int max_iterations = 10);

}  // namespace acvo
