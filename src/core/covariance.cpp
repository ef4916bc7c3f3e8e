#include "acvo/covariance.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "acvo/solver.hpp"

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

std::optional<Matrix6d> motionCovariance(const SolverResult& s, const SolverParams& solver,
                                         double covariance_scale, std::size_t moving_points) {
  // The curvature is negative definite at a maximum: its negative is the information.
  const Matrix6d info = -s.hessian;
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
  // Neighbouring pairs of one point are far from independent measurements: the paper's
  // curvature sums nnz pairs, but the information comes from the moving points. Scaling by
  // pairs per point keeps one calibration valid whether colour lets few or many pairs through
  // (measured: without it the flat-colour room's errors were 5x the textured room's relative
  // to -H^-1). coarse_to_fine's information already weighs each point by its own kernel,
  // whatever the number of its pairs (measured: with the factor the flat-colour room's errors
  // were 2.8x smaller than the textured room's relative to the covariance, without it 1.x).
  const double pairs_per_point = solver.ell_policy == EllPolicy::kCoarseToFine
                                     ? 1.0
                                     : double(std::max<std::size_t>(s.nnz, 1)) /
                                           double(std::max<std::size_t>(moving_points, 1));
  const Matrix6d cov = eig.eigenvectors() * lambda.cwiseInverse().asDiagonal() *
                       eig.eigenvectors().transpose() * (covariance_scale * pairs_per_point);
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
