#include "covariance.hpp"

namespace acvo_ros {

Covariance6 originCovariance() {
  return Covariance6::Identity() * kOriginVariance;
}

Covariance6 lostCovariance() {
  return Covariance6::Identity() * kLostVariance;
}

Covariance6 toRosOrder(const Covariance6& rotation_first) {
  // Permutation that swaps the two 3-blocks: P = [0 I; I 0], P C P^T.
  Covariance6 p = Covariance6::Zero();
  p.topRightCorner<3, 3>().setIdentity();
  p.bottomLeftCorner<3, 3>().setIdentity();
  return p * rotation_first * p.transpose();
}

Covariance6 rotate(const Covariance6& c, const Eigen::Matrix3d& a_from_b) {
  Covariance6 r = Covariance6::Zero();
  r.topLeftCorner<3, 3>() = a_from_b;
  r.bottomRightCorner<3, 3>() = a_from_b;
  return r * c * r.transpose();
}

Covariance6 sanitise(const Covariance6& c) {
  if (!c.allFinite() || (c.diagonal().array() < 0.0).any()) return lostCovariance();
  return 0.5 * (c + c.transpose());
}

Covariance6 accumulate(const Covariance6& pose, const Covariance6& relative,
                       const Eigen::Matrix3d& odom_from_frame) {
  return pose + rotate(sanitise(relative), odom_from_frame);
}

std::array<double, 36> toArray(const Covariance6& c) {
  std::array<double, 36> out{};
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) out[6 * r + k] = c(r, k);
  return out;
}

}  // namespace acvo_ros
