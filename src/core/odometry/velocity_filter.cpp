#include "acvo/velocity_filter.hpp"

#include <algorithm>

#include <Eigen/Dense>

namespace acvo {

void VelocityFilter::add(const Vector6d& sample, Matrix6d& mean_square, int& count) const {
  if (!sample.allFinite()) return;
  ++count;
  const double rate = 1.0 / std::min(double(count), memory_);
  mean_square += rate * (sample * sample.transpose() - mean_square);
}

Matrix6d VelocityFilter::gain() const {
  // Both moments start from the same negligible amount in every direction: where the samples
  // say nothing yet (no sample, or a camera that never moved along a direction) the two
  // estimates weigh alike, and the solve stays defined.
  const double prior = 1e-9 * (change_ + correction_).trace() + 1e-30;
  const Matrix6d change = change_ + prior * Matrix6d::Identity();
  const Matrix6d sum = change + correction_ + prior * Matrix6d::Identity();
  // change * sum^-1, both symmetric.
  return sum.ldlt().solve(change).transpose();
}

}  // namespace acvo
