// Seeded random numbers for the synthetic generator.
//
// Everything here is written out by hand (splitmix64, Box-Muller) rather than taken from
// <random>'s distributions, whose output is implementation-defined: a seed must give the same
// scene, trajectory and noise, bit for bit, with any standard library and any thread count.
#pragma once

#include <cmath>
#include <cstdint>

namespace acvo::synth {

// splitmix64's finaliser: a bijective 64-bit mix, good enough to hash counters into noise.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Combines a seed with a stream index (frame, row, ...) into an independent seed.
inline std::uint64_t hashCombine(std::uint64_t seed, std::uint64_t value) {
  return mix64(seed ^ mix64(value + 0x632be59bd9b4e019ull));
}

// A small sequential generator (splitmix64). Cheap to create, so each image row or each
// scene element can own one seeded from its index: results do not depend on scheduling.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}

  std::uint64_t next() {
    state_ += 0x9e3779b97f4a7c15ull;
    return mix64(state_);
  }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n).
  int index(int n) { return static_cast<int>(uniform() * n); }
  // Standard normal by Box-Muller (one of the pair is dropped: simpler).
  double gaussian() {
    const double u1 = 1.0 - uniform();  // (0, 1]: log stays finite
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  // Zero mean, unit variance, close to normal: the sum of four uniforms (Irwin-Hall) from
  // one 64-bit draw, bounded by +-2 sqrt(3). Several times cheaper than gaussian(); used
  // for per-pixel sensor noise, where a million draws per frame are needed.
  double pixelNoise() {
    const std::uint64_t x = next();
    double sum = 0.0;
    for (int k = 0; k < 4; ++k) sum += static_cast<double>((x >> (16 * k)) & 0xffff) + 0.5;
    return (sum * (1.0 / 65536.0) - 2.0) * 1.7320508075688772;
  }

 private:
  std::uint64_t state_;
};

}  // namespace acvo::synth
