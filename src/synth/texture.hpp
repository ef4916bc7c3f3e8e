// Procedural surface colour: multi-scale value noise with a checker or stripe overlay, or a
// flat colour.
//
// Textures are functions of 2-D surface coordinates in metres, so a surface point keeps its
// colour from every viewpoint (brightness constancy holds exactly, there is no lighting).
// Detail finer than about two pixels is faded out to the local mean using the pixel's
// footprint on the surface: a cheap anti-aliasing that keeps far, grazing surfaces from
// turning into pixel noise while near surfaces show gradients at every scale.
#pragma once

#include <cstdint>

#include <Eigen/Core>

namespace acvo::synth {

enum class Pattern { kNone, kChecker, kStripes };

struct Material {
  Eigen::Vector3d base{128, 128, 128};    // BGR in [0, 255]
  Eigen::Vector3d accent{128, 128, 128};  // BGR; the noise blends base -> accent
  bool textured = false;                  // false: the colour is `base` everywhere
  double noise_wavelength = 1.0;          // metres, coarsest noise octave; each next halves
  int noise_octaves = 8;                  // 4 coarse (colour and shading), the rest grain
  Pattern pattern = Pattern::kNone;
  double pattern_period = 0.2;    // metres (checker square pair / stripe pair)
  double pattern_angle = 0.0;     // radians, stripe direction in surface coordinates
  double pattern_contrast = 0.3;  // relative brightness swing of the pattern
  std::uint64_t seed = 0;         // noise lattice
};

// Smooth 2-D value noise in [0, 1], lattice spacing 1 (quintic interpolation of hashed
// lattice values: continuous first and second derivatives).
double valueNoise(double x, double y, std::uint64_t seed);

// Colour (BGR, [0, 255]) of `material` at surface coordinates (s, t) metres, for a pixel
// whose footprint on the surface is `footprint` metres. `brightness` scales the result
// (used to tell the faces of one box apart).
Eigen::Vector3d surfaceColour(const Material& material, double s, double t, double footprint,
                              double brightness = 1.0);

}  // namespace acvo::synth
