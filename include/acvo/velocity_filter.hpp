// The camera's velocity over a frame's colour/depth delay (docs/method.md §7), from two
// estimates: the last frame's motion (a prediction, wrong by the change of velocity since) and
// this frame's own coarse registration (a measurement, wrong by the coarse levels' error).
// Each is weighed by what the other misses, as a Kalman filter weighs prediction and
// measurement; both errors are measured on the sequence itself, so a smooth camera trusts the
// prediction and a hand-held one its own motion, with no threshold to tune.
#pragma once

#include <Eigen/Core>

#include "acvo/se3.hpp"

namespace acvo {

class VelocityFilter {
 public:
  // `memory`: the number of frames the running mean squares average over.
  explicit VelocityFilter(double memory = 10.0) : memory_(memory) {}

  // Velocities are twists per second (logSE3 of a motion over its interval). Returns
  // predicted + gain * (measured - predicted), `gain` as gain() gives it.
  static Vector6d blend(const Matrix6d& gain, const Vector6d& predicted,
                        const Vector6d& measured) {
    return predicted + gain * (measured - predicted);
  }
  // The weight of the measurement: the Kalman gain change (change + correction)^-1 of the two
  // errors' running second moments, as full 6x6 matrices (a coarse registration's rotation
  // and translation errors are correlated). Half of each where nothing was seen yet.
  Matrix6d gain() const;

  // The change of velocity from one tracked frame to the next (the prediction's error).
  void addChange(const Vector6d& change) { add(change, change_, changes_); }
  // A frame's final velocity less its coarse levels' (the measurement's error).
  void addCorrection(const Vector6d& correction) { add(correction, correction_, corrections_); }
  void reset() { *this = VelocityFilter(memory_); }
  // The running second moment of the velocity's change between tracked frames (twists per
  // second, rotation first): how far a constant-velocity prediction has been missing lately.
  const Matrix6d& changeMoment() const { return change_; }
  int changes() const { return changes_; }  // the samples it has seen since the last reset

 private:
  // Running second moments: the mean of the first `memory` samples' outer products, then an
  // exponential average over `memory` samples.
  void add(const Vector6d& sample, Matrix6d& mean_square, int& count) const;

  double memory_;
  Matrix6d change_ = Matrix6d::Zero();
  Matrix6d correction_ = Matrix6d::Zero();
  int changes_ = 0;
  int corrections_ = 0;
};

}  // namespace acvo
