#include "covariance.hpp"

namespace acvo_ros {

Covariance6 toRosOrder(const Covariance6& rotation_first) {
  // Permutation that swaps the two 3-blocks: P = [0 I; I 0], P C P^T.
  Covariance6 p = Covariance6::Zero();
  p.topRightCorner<3, 3>().setIdentity();
  p.bottomLeftCorner<3, 3>().setIdentity();
  return p * rotation_first * p.transpose();
}

std::array<double, 36> toArray(const Covariance6& c) {
  std::array<double, 36> out{};
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) out[6 * r + k] = c(r, k);
  return out;
}

}  // namespace acvo_ros
