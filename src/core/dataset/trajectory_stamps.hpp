// Trajectories ordered by stamp, as the TUM RGB-D benchmark tools read them: shared by the
// evaluation (evaluation.cpp) and the clock-offset search (clock_offset.cpp).
#pragma once

#include <cstddef>
#include <vector>

#include "acvo/dataset/tum.hpp"

namespace acvo::detail {

// Indices of the poses sorted by stamp; of poses with equal stamps only the last one given stays
// (the tools read trajectories into dictionaries keyed by stamp).
std::vector<std::size_t> uniqueByStamp(const Trajectory& trajectory);
// The poses of uniqueByStamp, in its order.
Trajectory byStamp(const Trajectory& trajectory);
std::vector<double> stampsOf(const Trajectory& trajectory);
// The median (of an even count, the mean of the two middle values).
double median(std::vector<double> values);
// The median of the intervals between consecutive stamps.
double medianInterval(const std::vector<double>& stamps);

}  // namespace acvo::detail
