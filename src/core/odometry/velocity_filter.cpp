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
  // Six samples at the least: fewer cannot span the six directions of a twist.
  constexpr int kMinSamples = 6;
  if (changes_ < kMinSamples || corrections_ < kMinSamples) return Matrix6d::Identity();
  // A ridge far below either error keeps the solve defined where the samples happened to
  // span fewer directions (a camera that never moved along one).
  const Matrix6d sum = change_ + correction_ +
                       (1e-9 * (change_ + correction_).trace() + 1e-30) * Matrix6d::Identity();
  // change * sum^-1, both symmetric.
  return sum.ldlt().solve(change_).transpose();
}

Vector6d VelocityFilter::blend(const Vector6d& predicted, const Vector6d& measured) const {
  return predicted + gain() * (measured - predicted);
}

}  // namespace acvo
