#include "acvo/math/order_statistics.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

namespace acvo {
namespace {

constexpr std::size_t kSample = 64;       // values the two pivots are read from
constexpr std::size_t kGap = 6;           // sample ranks between the wanted one and each pivot
constexpr std::size_t kNarrowFrom = 256;  // fewer values: std::nth_element alone
constexpr double kInf = std::numeric_limits<double>::infinity();

// The pivots kGap sample ranks either side of rank `at` of a sorted sample (the sample's ends:
// no bound).
template <typename Value>
std::pair<double, double> pivotsAround(const std::array<Value, kSample>& sample, std::size_t at,
                                       double (*value)(const Value&)) {
  return {at >= kGap ? value(sample[at - kGap]) : -kInf,
          at + kGap < kSample ? value(sample[at + kGap]) : kInf};
}

double valueOf(const double& x) { return x; }
double firstOf(const std::pair<double, double>& p) { return p.first; }

}  // namespace

double kthSmallest(double* first, double* last, std::size_t k) {
  std::size_t n = std::size_t(last - first);
  while (n > kNarrowFrom) {
    std::array<double, kSample> sample;
    for (std::size_t i = 0; i < kSample; ++i) sample[i] = first[i * n / kSample];
    std::sort(sample.begin(), sample.end());
    const auto [lo, hi] = pivotsAround(sample, k * kSample / n, valueOf);
    // The values in [lo, hi] to the front, counting those below: every element is swapped and
    // both tests are added, whatever their outcome.
    std::size_t below = 0, kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double x = first[i];
      below += std::size_t(x < lo);
      std::swap(first[kept], first[i]);
      kept += std::size_t((x >= lo) & (x <= hi));
    }
    // A sample that missed the rank, or values all alike: std::nth_element on what is left.
    if (k < below || k >= below + kept || kept == n) break;
    k -= below;
    n = kept;
  }
  std::nth_element(first, first + k, first + n);
  return first[k];
}

namespace {

using PairIterator = std::vector<std::pair<double, double>>::iterator;

// Narrows [lo, hi) (weight in_range, `below` the weight of the smaller pairs before lo) to the
// pairs between two pivots around the sample's own crossing of `half`, as kthSmallest narrows,
// while the crossing stays among them and they are fewer: the kept pairs are moved to the front
// and hi and below follow.
void narrowToCrossing(PairIterator lo, PairIterator& hi, double& below, double in_range,
                      double half) {
  while (std::size_t(hi - lo) > kNarrowFrom) {
    const std::size_t n = std::size_t(hi - lo);
    std::array<std::pair<double, double>, kSample> sample;
    for (std::size_t i = 0; i < kSample; ++i) sample[i] = lo[std::ptrdiff_t(i * n / kSample)];
    std::sort(sample.begin(), sample.end());
    double sample_weight = 0.0;
    for (const auto& s : sample) sample_weight += s.second;
    const double want = (half - below) / in_range * sample_weight;
    std::size_t at = 0;
    for (double seen = sample[0].second; at + 1 < kSample && seen < want;) {
      seen += sample[++at].second;
    }
    const auto [v_lo, v_hi] = pivotsAround(sample, at, firstOf);
    double w_below = 0.0, w_kept = 0.0;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const auto [x, w] = lo[std::ptrdiff_t(i)];
      const bool keep = (x >= v_lo) & (x <= v_hi);
      w_below += double(x < v_lo) * w;
      w_kept += double(keep) * w;
      std::swap(lo[std::ptrdiff_t(kept)], lo[std::ptrdiff_t(i)]);
      kept += std::size_t(keep);
    }
    // The crossing outside [v_lo, v_hi] (a sample that missed it), or no progress: the
    // quickselect on what is left.
    if (below + w_below >= half || !(below + w_below + w_kept >= half) || kept == n) break;
    below += w_below;
    in_range = w_kept;
    hi = lo + std::ptrdiff_t(kept);
  }
}

// A weighted quickselect of the crossing of `half` in [lo, hi) (`below` the weight of the
// smaller pairs before lo): one three-way partition per pass, summing the weights below and at
// the pivot as it goes. Rounding can leave the crossing past the last pair: the largest of
// [first, hi) then.
double weightedQuickselect(PairIterator first, PairIterator lo, PairIterator hi, double below,
                           double half) {
  const auto end = hi;
  while (hi - lo > 1) {
    const double a = lo->first, b = lo[(hi - lo) / 2].first, c = (hi - 1)->first;
    const double pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
    // [lo, less) < pivot, [less, p) == pivot, [greater, hi) > pivot.
    auto less = lo, p = lo, greater = hi;
    double w_less = 0.0, w_equal = 0.0;
    while (p != greater) {
      if (p->first < pivot) {
        w_less += p->second;
        std::iter_swap(less++, p++);
      } else if (pivot < p->first) {
        std::iter_swap(p, --greater);
      } else {
        w_equal += p->second;
        ++p;
      }
    }
    if (below + w_less >= half) {
      hi = less;
    } else if (below + w_less + w_equal >= half) {
      return pivot;
    } else {
      below += w_less + w_equal;
      lo = greater;
    }
  }
  return lo != end ? lo->first : std::max_element(first, end)->first;
}

}  // namespace

double weightedMedian(std::vector<std::pair<double, double>>& pairs) {
  double total = 0.0;
  for (const auto& p : pairs) total += p.second;
  const double half = 0.5 * total;
  const auto lo = pairs.begin();
  auto hi = pairs.end();
  double below = 0.0;  // the weight of the pairs before lo, all smaller
  narrowToCrossing(lo, hi, below, total, half);  // [lo, hi) weighs `total` at first
  return weightedQuickselect(pairs.begin(), lo, hi, below, half);
}

}  // namespace acvo
