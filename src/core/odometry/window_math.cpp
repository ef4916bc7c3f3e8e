// The window's cost, gradient and Gauss-Newton steps (window.hpp, docs/method.md §7.7).
#include "acvo/odometry/window.hpp"

#include <Eigen/Cholesky>

namespace acvo {

Vector6d linkResidual(const std::vector<Eigen::Isometry3d>& poses, const WindowLink& link) {
  return logSE3(poses[link.fixed].inverse() * poses[link.moving] * link.measured.inverse());
}

namespace {

// r and its Jacobians with respect to left perturbations of the fixed and the moving pose:
// T_f^-1 exp(-e_f) exp(e_m) T_m = exp(Ad(T_f^-1) (e_m - e_f)) T_f^-1 T_m to first order, so
// dr/de_m = J^-1(r) Ad(T_f^-1) = -dr/de_f.
struct Linearised {
  Vector6d r;
  Matrix6d d_moving;
};

Linearised linearise(const std::vector<Eigen::Isometry3d>& poses, const WindowLink& link) {
  Linearised l;
  l.r = linkResidual(poses, link);
  l.d_moving = leftJacobianInverseSE3(l.r) * adjointSE3(poses[link.fixed].inverse());
  return l;
}

}  // namespace

std::optional<Matrix6d> centreInformation(const Matrix6d& covariance,
                                          const Eigen::Isometry3d& measured) {
  const Matrix6d to_right = adjointSE3(measured.inverse());
  const Eigen::Matrix3d centre_covariance =
      (to_right * covariance * to_right.transpose()).bottomRightCorner<3, 3>();
  if (!centre_covariance.allFinite()) return std::nullopt;
  const Eigen::LLT<Eigen::Matrix3d> llt(0.5 * (centre_covariance + centre_covariance.transpose()));
  if (llt.info() != Eigen::Success) return std::nullopt;
  Matrix6d right_information = Matrix6d::Zero();
  right_information.bottomRightCorner<3, 3>() = llt.solve(Eigen::Matrix3d::Identity());
  return to_right.transpose() * right_information * to_right;
}

double windowCost(const std::vector<Eigen::Isometry3d>& poses,
                  const std::vector<WindowLink>& links) {
  double cost = 0.0;
  for (const WindowLink& link : links) {
    const Vector6d r = linkResidual(poses, link);
    cost += 0.5 * r.dot(link.information * r);
  }
  return cost;
}

Eigen::VectorXd windowGradient(const std::vector<Eigen::Isometry3d>& poses,
                               const std::vector<WindowLink>& links) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(6 * Eigen::Index(poses.size()));
  for (const WindowLink& link : links) {
    const Linearised l = linearise(poses, link);
    const Vector6d d = l.d_moving.transpose() * (link.information * l.r);
    g.segment<6>(6 * link.moving) += d;
    g.segment<6>(6 * link.fixed) -= d;
  }
  return g;
}

int refineWindow(std::vector<Eigen::Isometry3d>& poses, const std::vector<WindowLink>& links,
                 int held, int max_iterations) {
  // Pose k >= held is unknown number k - held.
  const Eigen::Index n = Eigen::Index(poses.size()) - held;
  if (n <= 0 || links.empty()) return 0;
  for (int iteration = 1; iteration <= max_iterations; ++iteration) {
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(6 * n, 6 * n);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(6 * n);
    for (const WindowLink& link : links) {
      const Linearised l = linearise(poses, link);
      const Matrix6d JtL = l.d_moving.transpose() * link.information;
      const Matrix6d block = JtL * l.d_moving;
      const Vector6d d = JtL * l.r;
      const Eigen::Index m = 6 * (link.moving - held), f = 6 * (link.fixed - held);
      const bool moving_free = link.moving >= held, fixed_free = link.fixed >= held;
      if (moving_free) {
        H.block<6, 6>(m, m) += block;
        g.segment<6>(m) += d;
      }
      if (fixed_free) {
        H.block<6, 6>(f, f) += block;
        g.segment<6>(f) -= d;
      }
      if (moving_free && fixed_free) {
        H.block<6, 6>(m, f) -= block;
        H.block<6, 6>(f, m) -= block;
      }
    }
    // A pose no link reaches has a zero block: held where it is.
    for (Eigen::Index k = 0; k < 6 * n; ++k) {
      if (H(k, k) == 0.0) H(k, k) = 1.0;
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
    if (ldlt.info() != Eigen::Success) return iteration - 1;
    const Eigen::VectorXd step = -ldlt.solve(g);
    if (!step.allFinite()) return iteration - 1;
    for (Eigen::Index k = 0; k < n; ++k) {
      Eigen::Isometry3d& pose = poses[std::size_t(k + held)];
      pose = normalized(expSE3(step.segment<6>(6 * k)) * pose);
    }
    if (step.lpNorm<Eigen::Infinity>() < 1e-9) return iteration;
  }
  return max_iterations;
}

}  // namespace acvo
