// Covariances of motions and poses (docs/method.md §7).
#include "acvo/odometry/covariance.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>


namespace acvo {

Matrix6d rotateCovariance(const Matrix6d& c, const Eigen::Matrix3d& a_from_b) {
  Matrix6d r = Matrix6d::Zero();
  r.topLeftCorner<3, 3>() = a_from_b;
  r.bottomRightCorner<3, 3>() = a_from_b;
  return r * c * r.transpose();
}

Matrix6d sanitiseCovariance(const Matrix6d& c) {
  if (!c.allFinite() || (c.diagonal().array() < 0.0).any()) return lostCovariance();
  return 0.5 * (c + c.transpose());
}

std::optional<Matrix6d> scaledInverseInformation(const Matrix6d& info, double covariance_scale) {
  Eigen::SelfAdjointEigenSolver<Matrix6d> eig(0.5 * (info + info.transpose()));
  Vector6d lambda = eig.eigenvalues();
  const double floor = 1e-12 * std::max(lambda.maxCoeff(), 1e-300);
  bool degenerate = false;
  for (int k = 0; k < 6; ++k) {
    if (!(lambda[k] > floor)) {
      lambda[k] = floor;
      degenerate = true;
    }
  }
  const Matrix6d cov = eig.eigenvectors() * lambda.cwiseInverse().asDiagonal() *
                       eig.eigenvectors().transpose() * covariance_scale;
  if (degenerate || !cov.allFinite()) return std::nullopt;
  return cov;
}

Matrix6d lostGrowth(double seconds, const OdometryParams& params) {
  const double t = std::max(seconds, 0.0);
  const double rotation = params.lost_angular_speed * M_PI / 180.0 * t;
  const double translation = params.lost_speed * t;
  Vector6d diagonal;
  diagonal << Eigen::Vector3d::Constant(rotation * rotation),
      Eigen::Vector3d::Constant(translation * translation);
  return diagonal.asDiagonal();
}

}  // namespace acvo
