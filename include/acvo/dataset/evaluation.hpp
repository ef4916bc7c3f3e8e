// Trajectory evaluation with the semantics of the TUM RGB-D benchmark tools:
// relative pose error as evaluate_rpe.py --fixed_delta, absolute trajectory error as
// evaluate_ate.py (greedy stamp association, Horn alignment without scale).
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "acvo/dataset/tum.hpp"

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

// evaluate_rpe.py --fixed_delta (scale 1, every pair used: the tool's random sampling above
// 10000 pairs is not reproduced). For each estimate index i, j is the index whose delta-unit
// value is closest to value_i + delta; the pair is kept when j is not the last index and both
// stamps, plus `offset` (s; the tool's --offset), have a ground-truth stamp within twice the
// median ground-truth interval, the nearest one used. Error E = (P_i^-1 P_j)(G_i^-1 G_j)^-1:
// translation |t(E)|, rotation angle of R(E). Poses with equal stamps keep the last one, as the
// tool's dictionaries do. Throws std::runtime_error when fewer than two pairs can be compared.
RpeResult computeRpe(const Trajectory& groundtruth, const Trajectory& estimate, double delta = 1.0,
                     DeltaUnit unit = DeltaUnit::kSeconds, double offset = 0.0);

struct AteResult {
  ErrorStats trans;  // m, residual position norms after alignment
  // Maps estimate positions onto ground-truth positions (rotation + translation, no scale).
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();
  // Associated (ground-truth index, estimate index), in the order of the trajectories given.
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  std::size_t pairs = 0;
};

// evaluate_ate.py: stamps associated greedily by smallest difference (< max_difference, each
// used once; `offset` s added to the estimate's stamps, the tool's --offset), Horn's closed-form
// alignment of the estimate positions onto the ground truth. Throws std::runtime_error when fewer
// than two stamps associate.
AteResult computeAte(const Trajectory& groundtruth, const Trajectory& estimate,
                     double max_difference = 0.02, double offset = 0.0);

// The offset between a reference's clock and the estimates' stamps: the `offset` of the two
// functions above at which the estimates' turn from each frame to the next agrees best with the
// reference's over the same instants. A camera's stamps may say when a frame reached the
// computer, not when it was exposed, and a motion-capture system keeps its own clock: over a
// 1-s window the reference then measures a motion a few milliseconds apart from the
// estimate's, an error every method is charged with, and the more precise one the more in
// proportion. Frame-to-frame turns are what a reference and an estimate both measure without a
// common world frame or scale; the reference is interpolated (slerp) at each stamp + offset.
struct ClockOffset {
  double offset = 0.0;      // s, to be added to the estimates' stamps
  std::size_t turns = 0;    // frame-to-frame turns compared, over every estimate
  // Per estimate, the RMS angle between its turns and the reference's, at offset 0 and at the
  // offset found (deg).
  std::vector<double> turn_rms_at_zero_deg, turn_rms_deg;
};

// Searches [-max_offset, max_offset] (0.5 ms steps, then a parabola through the best three).
// Each estimate's mean square turn error, as a function of the offset, is divided by its own
// least value before they are summed: a method that lost its way has a flat curve and adds
// little, a precise one a sharp minimum. `weights` (one per estimate, positive; empty: 1 each)
// scale the curves in the sum: 1/K for each of a method's K settings gives every method one
// vote, however many settings it ran in (acvo_compare). Only turns whose reference exists at
// every offset searched are compared (no gap over twice the median reference interval). Throws
// std::invalid_argument for weights of another count or not positive, and std::runtime_error
// where the reference has no clock of its own: it is not sampled at least twice as often as the
// frames (median intervals; a reference of one pose per frame, as 7-Scenes' and the synthetic
// sequences'), or more than 90% of an estimate's stamps are reference stamps to 0.1 ms (such a
// reference with the frames kept one in K); also when fewer than 10 turns can be compared, when
// the best offset is at the search's edge, or when the reference turns too little for the offset
// to show (the curve's ends within 5% of its least value).
ClockOffset estimateClockOffset(const Trajectory& groundtruth,
                                const std::vector<Trajectory>& estimates,
                                const std::vector<double>& weights = {},
                                double max_offset = 0.05);

}  // namespace acvo
