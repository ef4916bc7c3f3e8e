// The order statistics the direct terms read (acvo/math/order_statistics.hpp): the answers of a
// sort, on values in no order, with ties, all alike, already sorted or reversed, and on sizes
// either side of where the narrowing pass starts.
#include <algorithm>
#include <cstddef>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "acvo/math/order_statistics.hpp"

namespace acvo {
namespace {

enum class Shape { kSpread, kTies, kAlike, kSorted, kReversed, kOneFar };

std::vector<double> draw(Shape shape, int n, std::mt19937& rng) {
  std::lognormal_distribution<double> spread(0.0, 2.0);
  std::uniform_int_distribution<int> few(0, 5);
  std::vector<double> v(std::size_t(n), 0.0);
  for (double& x : v) {
    switch (shape) {
      case Shape::kTies: x = few(rng); break;
      case Shape::kAlike: x = 3.0; break;
      default: x = spread(rng);
    }
  }
  if (shape == Shape::kSorted) std::sort(v.begin(), v.end());
  if (shape == Shape::kReversed) std::sort(v.rbegin(), v.rend());
  if (shape == Shape::kOneFar) v[std::size_t(n / 3)] = 1e300;
  return v;
}

constexpr Shape kShapes[] = {Shape::kSpread, Shape::kTies,     Shape::kAlike,
                             Shape::kSorted, Shape::kReversed, Shape::kOneFar};

TEST(OrderStatistics, KthSmallestIsTheSortedValueAndKeepsTheValues) {
  std::mt19937 rng(3);
  for (int n : {1, 2, 7, 255, 256, 257, 1000, 3001, 20000}) {
    for (Shape shape : kShapes) {
      const std::vector<double> values = draw(shape, n, rng);
      std::vector<double> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      for (std::size_t k : {std::size_t(0), std::size_t(n / 4), std::size_t(n / 2),
                            std::size_t(n - 1)}) {
        std::vector<double> v = values;
        EXPECT_EQ(kthSmallest(v.data(), v.data() + v.size(), k), sorted[k])
            << "n " << n << " shape " << int(shape) << " k " << k;
        std::sort(v.begin(), v.end());
        EXPECT_EQ(v, sorted) << "n " << n << " shape " << int(shape);  // reordered only
      }
    }
  }
}

// The learned scales' weighted median equals the answer of a sort and a running sum, on random
// values with ties and without, zero weights, equal weights and one weight that outweighs all
// the rest, on sizes below and above the narrowing's.
TEST(OrderStatistics, WeightedMedianEqualsTheSortedAnswer) {
  auto sorted = [](std::vector<std::pair<double, double>> v) {
    std::sort(v.begin(), v.end());
    double total = 0.0, seen = 0.0;
    for (const auto& p : v) total += p.second;
    for (const auto& p : v) {
      seen += p.second;
      if (seen >= 0.5 * total) return p.first;
    }
    return v.back().first;
  };
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> value(0, 40);  // ties
  std::lognormal_distribution<double> spread(0.0, 2.0);
  std::uniform_real_distribution<double> weight(0.0, 1.0);
  for (int n : {1, 2, 3, 10, 101, 2000, 5000}) {
    for (int trial = 0; trial < 24; ++trial) {
      std::vector<std::pair<double, double>> v;
      const bool ties = trial % 8 < 4;
      for (int k = 0; k < n; ++k) {
        const double w = trial % 4 == 0 ? 0.0 : (trial % 4 == 1 ? 1.0 : weight(rng));
        v.emplace_back(ties ? 0.1 * value(rng) : spread(rng), w);
      }
      if (trial % 4 == 3) v[std::size_t(n / 2)].second = 1e6;
      const double expected = sorted(v);
      EXPECT_EQ(weightedMedian(v), expected) << "n " << n << " trial " << trial;
    }
  }
}

// Weights that pile up at one end: the sample's crossing misses the true one, which the
// narrowing must notice (the answer is the largest value's neighbourhood, not the sample's).
TEST(OrderStatistics, WeightedMedianWhenTheSampleMissesTheCrossing) {
  std::vector<std::pair<double, double>> v;
  for (int k = 0; k < 4000; ++k) v.emplace_back(double(k), k >= 3990 ? 1000.0 : 1.0);
  std::shuffle(v.begin(), v.end(), std::mt19937(9));
  // Total 3990 + 10000 = 13990, half 6995: 3990 + 1000 * 3 = 6990 < 6995 <= 7990 at k = 3993.
  EXPECT_EQ(weightedMedian(v), 3993.0);
}

}  // namespace
}  // namespace acvo
