// Nearest-stamp association of two sorted stamp lists within a tolerance (TUM's associate.py).
#include "stamp_association.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace acvo::detail {

std::vector<std::pair<std::size_t, std::size_t>> associateStamps(const std::vector<double>& first,
                                                                 const std::vector<double>& second,
                                                                 double max_difference) {
  // Only second stamps near a first stamp can be candidates: search a sorted index of them.
  std::vector<std::size_t> order(second.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return second[a] < second[b]; });

  struct Candidate {
    double difference;
    std::size_t first, second;
  };
  std::vector<Candidate> candidates;
  for (std::size_t f = 0; f < first.size(); ++f) {
    const double t = first[f];
    // A window twice as wide as needed, so that rounding at its edges loses no candidate.
    auto it = std::lower_bound(order.begin(), order.end(), t - 2 * max_difference,
                               [&](std::size_t k, double s) { return second[k] < s; });
    for (; it != order.end() && second[*it] <= t + 2 * max_difference; ++it) {
      const double difference = std::abs(t - second[*it]);
      if (difference < max_difference) candidates.push_back({difference, f, *it});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [&](const Candidate& a, const Candidate& b) {
    return std::make_tuple(a.difference, first[a.first], second[a.second], a.first, a.second) <
           std::make_tuple(b.difference, first[b.first], second[b.second], b.first, b.second);
  });

  std::vector<bool> first_used(first.size(), false), second_used(second.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const Candidate& c : candidates) {
    if (first_used[c.first] || second_used[c.second]) continue;
    first_used[c.first] = second_used[c.second] = true;
    matches.emplace_back(c.first, c.second);
  }
  std::stable_sort(matches.begin(), matches.end(),
                   [&](const auto& a, const auto& b) { return first[a.first] < first[b.first]; });
  return matches;
}

}  // namespace acvo::detail
