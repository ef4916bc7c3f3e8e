// Kinect-like degradations of an exact rendering.
//
// Depth, in this order: pixels at depth discontinuities are dropped (the sensor's pattern is
// shadowed and ambiguous there); axial noise with a standard deviation growing with z^2;
// disparity quantisation (1/8 pixel steps of a 7.5 cm baseline, 580 px focal structured
// light sensor: the depth step grows with z^2, about 3 mm at 1 m and 4.6 cm at 4 m); the
// measuring range (0 outside it); finally the depth image's own unit (1/depth_scale m).
// Colour: small noise per channel. Noise is near-Gaussian (Rng::pixelNoise: zero mean, the
// stated standard deviation, tails cut at 3.5 sigma). The depth noise is drawn per pixel, or,
// with correlation_px > 0, as a smooth field: a structured-light sensor matches its pattern over
// a window of pixels, so its errors come in blobs of neighbouring pixels that err together (the
// field is white noise smoothed by a Gaussian of correlation_px pixels, then scaled back to unit
// variance: neighbours d pixels apart correlate by exp(-d^2 / (4 correlation_px^2))).
//
// A sensor's fixed depth distortion (distortion_relative > 0): every frame's depth is scaled by
// 1 + distortion_relative D(u, v), D a smooth unit-variance field fixed to the image (drawn once
// from distortion_seed, correlated over an eighth of the image's width), as a structured-light
// sensor's calibration leaves a pattern of a few per mille that stays where it is in the image
// while the scene moves through it.
//
// The random numbers of row v come from hashCombine(seed, v): results are identical for
// any thread count.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

namespace acvo::synth {

struct KinectNoise {
  double sigma_base = 0.0012;             // m; sigma(z) = base + quadratic * (z - offset)^2
  double sigma_quadratic = 0.0019;        // 1/m
  double sigma_offset = 0.4;              // m
  double focal_baseline = 580.0 * 0.075;  // px * m, for the disparity d = focal_baseline / z
  double disparity_step = 1.0 / 8.0;      // px
  double min_depth = 0.4;                 // m; nearer -> 0
  double max_depth = 8.0;                 // m; farther -> 0
  // A pixel loses its depth when an 8-neighbour's true depth differs by more than
  // edge_jump_base + edge_jump_quadratic * z^2 (or has none).
  double edge_jump_base = 0.02;       // m
  double edge_jump_quadratic = 0.01;  // 1/m
  double colour_sigma = 1.5;          // 8-bit grey levels
  double correlation_px = 0.0;        // px; the depth noise's correlation length (0: per pixel)
  double distortion_relative = 0.0;   // the fixed distortion's standard deviation (0: none)
  std::uint64_t distortion_seed = 0;  // the sensor's: the same for every frame

  double depthSigma(double z) const {
    const double e = z - sigma_offset;
    return sigma_base + sigma_quadratic * e * e;
  }
};

// exact: CV_32FC1 metres, 0 = nothing seen. Returns CV_32FC1 metres, 0 = invalid, quantised to
// 1 / depth_scale metres when depth_scale > 1 (integer depth images).
cv::Mat degradeDepth(const cv::Mat& exact, const KinectNoise& noise, double depth_scale,
                     std::uint64_t seed);

// The fixed distortion's field D for an image of this size (unit variance, smooth).
cv::Mat distortionField(cv::Size size, std::uint64_t seed);

// colour: CV_32FC3, modified in place (not clamped: the 8-bit conversion saturates).
void addColourNoise(cv::Mat& colour, double sigma, std::uint64_t seed);

}  // namespace acvo::synth
