// Greedy nearest-timestamp association shared by the rgb/depth lists and the evaluator.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace acvo::detail {

// TUM's associate.py: every pair with |first - second| < max_difference is a candidate; the
// candidates are taken by increasing difference (ties: smaller first stamp, then smaller second
// stamp), each stamp used at most once. Returns (first index, second index) pairs sorted by the
// first stamp.
std::vector<std::pair<std::size_t, std::size_t>> associateStamps(const std::vector<double>& first,
                                                                 const std::vector<double>& second,
                                                                 double max_difference);

}  // namespace acvo::detail
