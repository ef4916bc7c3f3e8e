// Trajectories ordered by stamp (trajectory_stamps.hpp).
#include "trajectory_stamps.hpp"

#include <algorithm>
#include <numeric>

namespace acvo::detail {

std::vector<std::size_t> uniqueByStamp(const Trajectory& trajectory) {
  std::vector<std::size_t> order(trajectory.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return trajectory[a].stamp < trajectory[b].stamp;
  });
  std::vector<std::size_t> unique;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k + 1 < order.size() && trajectory[order[k + 1]].stamp == trajectory[order[k]].stamp) {
      continue;
    }
    unique.push_back(order[k]);
  }
  return unique;
}

Trajectory byStamp(const Trajectory& trajectory) {
  Trajectory sorted;
  for (const std::size_t k : uniqueByStamp(trajectory)) sorted.push_back(trajectory[k]);
  return sorted;
}

std::vector<double> stampsOf(const Trajectory& trajectory) {
  std::vector<double> stamps;
  for (const StampedPose& p : trajectory) stamps.push_back(p.stamp);
  return stamps;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double medianInterval(const std::vector<double>& stamps) {
  std::vector<double> intervals;
  for (std::size_t k = 1; k < stamps.size(); ++k) intervals.push_back(stamps[k] - stamps[k - 1]);
  return median(intervals);
}

}  // namespace acvo::detail
