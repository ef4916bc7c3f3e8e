// Trajectory evaluation with the semantics of the TUM RGB-D benchmark tools:
// relative pose error as evaluate_rpe.py --fixed_delta, absolute trajectory error as
// evaluate_ate.py (greedy stamp association, Horn alignment without scale).
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "acvo/tum.hpp"

namespace acvo {

// What the RPE delta counts: seconds, frames (estimate ordinals), metres travelled, or
// rotation accumulated (radians, degrees) along the estimate.
enum class DeltaUnit { kSeconds, kFrames, kMeters, kRadians, kDegrees };

// "s", "f", "m", "rad", "deg" (the TUM tool's spelling). Throws std::invalid_argument.
DeltaUnit deltaUnitFromString(const std::string& text);
std::string toString(DeltaUnit unit);

// Summary of a list of errors as the TUM tools print it (std is the population std, the
// median of an even count is the mean of the two middle values). All 0 for an empty list.
struct ErrorStats {
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;
  double min = 0.0;
  double max = 0.0;
  std::size_t count = 0;
};
ErrorStats errorStats(std::vector<double> values);

struct RpeResult {
  ErrorStats trans;    // m
  ErrorStats rot_deg;  // degrees
  std::size_t pairs = 0;
};

// evaluate_rpe.py --fixed_delta (offset 0, scale 1, every pair used: the tool's random
// sampling above 10000 pairs is not reproduced). For each estimate index i, j is the index
// whose delta-unit value is closest to value_i + delta; the pair is kept when j is not the last
// index and both stamps have a ground-truth stamp within twice the median ground-truth interval.
// Error E = (P_i^-1 P_j)(G_i^-1 G_j)^-1: translation |t(E)|, rotation angle of R(E).
// Poses with equal stamps keep the last one, as the tool's dictionaries do.
// Throws std::runtime_error when fewer than two pairs can be compared.
RpeResult computeRpe(const Trajectory& groundtruth, const Trajectory& estimate, double delta = 1.0,
                     DeltaUnit unit = DeltaUnit::kSeconds);

struct AteResult {
  ErrorStats trans;  // m, residual position norms after alignment
  // Maps estimate positions onto ground-truth positions (rotation + translation, no scale).
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();
  // Associated (ground-truth index, estimate index), in the order of the trajectories given.
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  std::size_t pairs = 0;
};

// evaluate_ate.py: stamps associated greedily by smallest difference (< max_difference, offset
// 0, each used once), Horn's closed-form alignment of the estimate positions onto the ground
// truth. Throws std::runtime_error when fewer than two stamps associate.
AteResult computeAte(const Trajectory& groundtruth, const Trajectory& estimate,
                     double max_difference = 0.02);

}  // namespace acvo
