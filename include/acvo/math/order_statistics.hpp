// Order statistics of the few thousand residuals that the direct terms' learned scales, their
// brightness and their edge fit read at every iteration of a registration. std::nth_element
// partitions around one pivot per round, and on values in no order it mispredicts about half
// of its comparisons: in `perf record` over teddy200 its medians and the weighted median were
// about a tenth of a frame. Here a pass without branches first keeps only the values between
// two pivots read from a sorted sample around the wanted rank (about a fifth of them, again
// while more than 256 are left), and std::nth_element finishes there. `acvo_bench_kernels
// --threads=1 --benchmark_filter=Median` (the upper median of a frame pair's 2755-3299
// photometric says): 24-31 us by std::nth_element, 11.5 us here.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace acvo {

// The k-th smallest (0-based) of [first, last), k < last - first, no NaN among them (the value
// std::nth_element(first, first + k, last) puts at first + k). Reorders the range.
double kthSmallest(double* first, double* last, std::size_t k);

// The smallest value v of the (value, weight) pairs whose weights up to v reach half of all (a
// sort's answer in linear time). Reorders the pairs, which must not be empty; no NaN, weights
// not negative. The terms' learned scales are weighted medians.
double weightedMedian(std::vector<std::pair<double, double>>& pairs);

}  // namespace acvo
