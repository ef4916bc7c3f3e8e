// How much the camera's velocity has been changing from one tracked frame to the next: the
// running second moment of those changes (twists per second, rotation first). A
// constant-velocity guess misses by about that change times the interval; the second start's
// check (odometry.hpp) asks whether a registration missed its guess unusually for this camera.
#pragma once

#include "acvo/math/se3.hpp"

namespace acvo {

class VelocityChanges {
 public:
  // `memory`: the number of frames the running mean square averages over.
  explicit VelocityChanges(double memory = 10.0) : memory_(memory) {}

  // A change of velocity between two tracked frames; a sample that is not finite is ignored.
  void add(const Vector6d& change);
  void reset() { *this = VelocityChanges(memory_); }
  // The mean of the first `memory` samples' outer products, then an exponential average over
  // `memory` samples.
  const Matrix6d& moment() const { return moment_; }
  int count() const { return count_; }  // the samples seen since the last reset

 private:
  double memory_;
  Matrix6d moment_ = Matrix6d::Zero();
  int count_ = 0;
};

}  // namespace acvo
