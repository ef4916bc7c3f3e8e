#include "synth/texture.hpp"

#include <algorithm>
#include <cmath>

#include "synth/random.hpp"

namespace acvo::synth {
namespace {

// A hashed value in [0, 1) per lattice point. One multiply-xorshift round is plenty for
// noise and half the cost of a full mix64, and texturing is most of the rendering time.
double latticeValue(std::int64_t ix, std::int64_t iy, std::uint64_t seed) {
  std::uint64_t h = seed ^ (static_cast<std::uint64_t>(ix) * 0x8cb92ba72f3d8dd7ull) ^
                    (static_cast<std::uint64_t>(iy) * 0xd6e8feb86659fd93ull);
  h ^= h >> 32;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 29;
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

double quintic(double f) {
  return f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
}

// valueNoise's body, inlinable into the octave loop (texturing dominates rendering time).
inline double noiseAt(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double u = quintic(x - fx), v = quintic(y - fy);
  const double a = latticeValue(ix, iy, seed), b = latticeValue(ix + 1, iy, seed);
  const double c = latticeValue(ix, iy + 1, seed), d = latticeValue(ix + 1, iy + 1, seed);
  return (a + (b - a) * u) * (1.0 - v) + (c + (d - c) * u) * v;
}

constexpr int kCoarseOctaves = 4;  // the rest of Material::noise_octaves are grain

double clamp01(double x) {
  return std::clamp(x, 0.0, 1.0);
}

// Weight of a feature of `wavelength` seen with pixels of `footprint`: 1 when it spans at
// least four pixels, 0 at two pixels or less (where it could only alias).
double detailWeight(double wavelength, double footprint) {
  return clamp01(0.5 * wavelength / footprint - 1.0);
}

// A square wave of `period` in [-1, 1] whose edges are about two footprints wide: a
// triangle wave (no trigonometry: it is evaluated per pixel), steepened and clipped.
double softSquare(double x, double period, double footprint) {
  const double phase = x / period + 0.25;
  const double triangle = 1.0 - 4.0 * std::abs(phase - std::floor(phase) - 0.5);
  return std::clamp(triangle * period / (4.0 * footprint), -1.0, 1.0);
}

// `octaves` octaves of value noise from `wavelength` down, each half the previous, around 0.5;
// octaves too fine for the footprint fade to their mean.
double fractalNoise(std::uint64_t seed, double s, double t, double footprint, double wavelength,
                    int octaves) {
  double sum = 0.0, total = 0.0, amplitude = 1.0;
  for (int k = 0; k < octaves; ++k) {
    const double w = detailWeight(wavelength, footprint);
    // Each octave gets its own lattice (seed + k) so octaves do not line up.
    const double n = w > 0.0 ? noiseAt(s / wavelength, t / wavelength, seed + k) : 0.5;
    sum += amplitude * (w * n + (1.0 - w) * 0.5);
    total += amplitude;
    amplitude *= 0.8;  // slow decay: fine octaves stay visible (gradients at many scales)
    wavelength *= 0.5;
  }
  // Sums of octaves cluster around 0.5: stretch the contrast back to most of [0, 1].
  return clamp01(0.5 + 3.0 * (sum / total - 0.5));
}

double patternValue(const Material& m, double s, double t, double footprint) {
  const double w = detailWeight(m.pattern_period, footprint);
  if (w <= 0.0) return 0.0;
  switch (m.pattern) {
    case Pattern::kChecker:
      return w * softSquare(s, m.pattern_period, footprint) *
             softSquare(t, m.pattern_period, footprint);
    case Pattern::kStripes: {
      const double along = s * std::cos(m.pattern_angle) + t * std::sin(m.pattern_angle);
      return w * softSquare(along, m.pattern_period, footprint);
    }
    case Pattern::kNone:
      break;
  }
  return 0.0;
}

}  // namespace

double valueNoise(double x, double y, std::uint64_t seed) {
  return noiseAt(x, y, seed);
}

Eigen::Vector3d surfaceColour(const Material& m, double s, double t, double footprint,
                              double brightness) {
  if (!m.textured) return (m.base * brightness).cwiseMax(0.0).cwiseMin(255.0);
  // Coarse octaves blend the two colours and drive brightness too (so that colours alike in
  // luminance still give grey-level gradients); the fine octaves, normalised on their own,
  // add a brightness grain that keeps near surfaces textured at the pixel scale.
  const int coarse = std::min(kCoarseOctaves, m.noise_octaves);
  const double n = fractalNoise(m.seed, s, t, footprint, m.noise_wavelength, coarse);
  const double grain =
      coarse < m.noise_octaves
          ? fractalNoise(m.seed + coarse, s, t, footprint, std::ldexp(m.noise_wavelength, -coarse),
                         m.noise_octaves - coarse)
          : 0.5;
  const double p = patternValue(m, s, t, footprint);
  const Eigen::Vector3d colour =
      (m.base + (m.accent - m.base) * n) *
      (brightness * (0.7 + 0.6 * n) * (0.7 + 0.6 * grain) * (1.0 + m.pattern_contrast * p));
  return colour.cwiseMax(0.0).cwiseMin(255.0);
}

}  // namespace acvo::synth
