#include "acvo/odometry/velocity_changes.hpp"

#include <algorithm>

namespace acvo {

void VelocityChanges::add(const Vector6d& change) {
  if (!change.allFinite()) return;
  ++count_;
  const double rate = 1.0 / std::min(double(count_), memory_);
  moment_ += rate * (change * change.transpose() - moment_);
}

}  // namespace acvo
