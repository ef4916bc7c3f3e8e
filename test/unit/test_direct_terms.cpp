// The default engine's last-level terms (direct_terms.hpp): each term alone converges to the
// true motion of a rendered pair (the photometric one in both directions), the point-to-plane
// term fades where depth is Kinect-noisy, the dense term tells noise per pixel from noise in
// blobs and gains where the first averages away, points on depth edges are left out at either
// end, the engine with them resolves motion far finer than its kernel alone, and the learned
// scales' weighted median is a sort's.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/params.hpp"
#include "acvo/registration/coarse_to_fine.hpp"
#include "acvo/registration/direct_terms.hpp"
#include "acvo/math/se3.hpp"
#include "synth/layout.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"

namespace acvo {
namespace {

// Camera b's pose in camera a's frame: 1 deg and 2 cm oblique.
Eigen::Isometry3d trueMotion() {
  const double k = M_PI / 180.0;
  return expSE3((Vector6d() << 0.6 * k, -0.5 * k, 0.6 * k, 0.012, -0.01, 0.012).finished());
}

// A reference's images: a moving cloud's and the whole smoothed grey image.
DirectImages referenceImages(const LabelledCloud& c) {
  DirectImages images = directImages(c);
  addReferenceImages(images, c);
  return images;
}

struct Pair {
  LabelledCloud a, b;  // b's points map into a's frame by trueMotion()
};

// b_brightness: b's colour that times a's, as a camera's auto exposure changes it; vignetting:
// both images' (RenderOptions::vignetting).
// noise_blobs_px: the depth noise in blobs of that size (KinectNoise::correlation_px).
Pair renderedPair(bool texture, bool noise, double b_brightness = 1.0, double vignetting = 0.0,
                  double noise_blobs_px = 0.0) {
  const synth::Scene scene = synth::makeScene({true, texture, 3});
  synth::RenderOptions ro;
  ro.noise = noise;
  ro.kinect.correlation_px = noise_blobs_px;
  ro.vignetting = vignetting;
  const Eigen::Isometry3d pose_a = synth::defaultStartPose();
  const SelectionParams sel;
  LabelledCloud a = buildLabelledCloud(synth::render(scene, pose_a, ro, 1).toFrame(), sel);
  ro.brightness = b_brightness;
  return {std::move(a),
          buildLabelledCloud(synth::render(scene, pose_a * trueMotion(), ro, 2).toFrame(), sel)};
}

// Each term at a transform, over the landings of b's points in a, as the engine calls them.
DirectSums photometricAt(const DirectImages& a, const DirectImages& b, const LabelledCloud& cloud_b,
                         const Eigen::Isometry3d& T) {
  return photometricSums(a, b, cloud_b, landings(a, b, cloud_b, T));
}
DirectSums pointToPlaneAt(const DirectImages& a, const DirectImages& b,
                          const LabelledCloud& cloud_b, const Eigen::Isometry3d& T,
                          double depth_noise) {
  return pointToPlaneSums(a, landings(a, b, cloud_b, T), depth_noise);
}

// The images with the depth grid, as the engine prepares them by default.
constexpr double kDepthNoise = 0.0025;
DirectImages denseReference(const LabelledCloud& c) {
  DirectImages images = directImages(c, true, kDepthNoise);
  addReferenceImages(images, c);
  return images;
}

struct Error {
  double mm, deg;
};
Error errorOf(const Eigen::Isometry3d& T) {
  const Vector6d e = logSE3(trueMotion().inverse() * T);
  return {1000.0 * e.tail<3>().norm(), e.head<3>().norm() * 180.0 / M_PI};
}

// Gauss-Newton with one term alone from a guess about a pixel off the truth.
template <typename Sums>
Eigen::Isometry3d iterate(Sums&& sums, int iterations, int min_used = 500) {
  const double k = M_PI / 180.0;
  Eigen::Isometry3d T =
      expSE3((Vector6d() << 0.1 * k, 0.1 * k, -0.1 * k, 0.002, 0.002, -0.002).finished()) *
      trueMotion();
  for (int i = 0; i < iterations; ++i) {
    const DirectSums s = sums(T);
    EXPECT_GT(s.used, min_used);
    T = normalized(expSE3(Eigen::LDLT<Matrix6d>(s.H).solve(s.g)) * T);
  }
  return T;
}

// A moving cloud's grey values are smoothed at its points' pixels only: the same values as the
// reference's whole smoothed image there, at the image's corners too (reflected border).
TEST(DirectTerms, PointGreyValuesAreTheSmoothedImagesAtTheirPixels) {
  LabelledCloud c = renderedPair(true, false).a;
  const int w = c.gray.cols, h = c.gray.rows;
  for (const cv::Point px : {cv::Point(0, 0), cv::Point(w - 1, h - 1), cv::Point(1, h - 2)}) {
    c.pixels.push_back(px);
    c.points.push_back(c.points.front());
    c.labels.push_back(c.labels.front());
  }
  const DirectImages ref = referenceImages(c);
  ASSERT_EQ(ref.point_intensity.size(), c.size());
  double worst = 0.0;
  for (std::size_t j = 0; j < c.size(); ++j) {
    const cv::Point& px = c.pixels[j];
    worst = std::max(worst, double(std::abs(ref.point_intensity[j] -
                                            ref.intensity.at<float>(px.y, px.x))));
  }
  std::printf("  point grey values against the smoothed image: worst %.2e grey levels\n", worst);
  EXPECT_LT(worst, 1e-4);  // float rounding of the same sums (measured 3e-5)
}

TEST(DirectTerms, PhotometricAloneConvergesToTheTrueMotion) {
  const Pair p = renderedPair(true, false);
  const DirectImages ref = referenceImages(p.a);
  const DirectImages mov = directImages(p.b);
  const Error start =
      errorOf(iterate([&](const auto& T) { return photometricAt(ref, mov, p.b, T); }, 0));
  const Error e =
      errorOf(iterate([&](const auto& T) { return photometricAt(ref, mov, p.b, T); }, 8));
  std::printf("  photometric: %.3f mm %.4f deg from %.3f mm %.4f deg\n", e.mm, e.deg, start.mm,
              start.deg);
  // Measured 0.044 mm / 0.0013 deg from 3.5 mm / 0.17 deg (the rendered texture is sampled
  // without anti-aliasing: no shift matches it exactly).
  EXPECT_LT(e.mm, 0.06);
  EXPECT_LT(e.deg, 0.0017);
}

// The reverse direction alone: a's points against b's whole smoothed image where they land,
// converging as the forward direction does; at the brightness the forward term measured where
// b's exposure differs. Without b's whole image it has nothing to read.
DirectSums reverseAt(const DirectImages& a, const LabelledCloud& cloud_a, const DirectImages& b,
                     const LabelledCloud& cloud_b, const Eigen::Isometry3d& T,
                     const Brightness& brightness = {}) {
  return reversePhotometricSums(a, cloud_a, b, cloud_b, T, brightness);
}

TEST(DirectTerms, ReversePhotometricAloneConvergesToTheTrueMotion) {
  const Pair p = renderedPair(true, false);
  const DirectImages ref = referenceImages(p.a);
  const DirectImages mov = directImages(p.b, false, 0.0, true);
  const DirectSums nothing = reverseAt(ref, p.a, directImages(p.b), p.b, trueMotion());
  EXPECT_EQ(nothing.used, 0);
  const Error e =
      errorOf(iterate([&](const auto& T) { return reverseAt(ref, p.a, mov, p.b, T); }, 8));
  std::printf("  reverse photometric: %.3f mm %.4f deg\n", e.mm, e.deg);
  // Measured 0.029 mm / 0.0007 deg (the forward direction 0.044 mm / 0.0013 deg).
  EXPECT_LT(e.mm, 1.3 * 0.029);
  EXPECT_LT(e.deg, 1.3 * 0.0007);

  const Pair darker = renderedPair(true, false, 0.8);
  const DirectImages dark_ref = referenceImages(darker.a);
  const DirectImages dark_mov = directImages(darker.b, false, 0.0, true);
  auto at = [&](const Eigen::Isometry3d& T, bool gain) {
    const Brightness b =
        photometricSums(dark_ref, dark_mov, darker.b, landings(dark_ref, dark_mov, darker.b, T),
                        gain)
            .brightness;
    return reverseAt(dark_ref, darker.a, dark_mov, darker.b, T, b);
  };
  const Error on = errorOf(iterate([&](const auto& T) { return at(T, true); }, 8));
  const Error off = errorOf(iterate([&](const auto& T) { return at(T, false); }, 8));
  std::printf("  reverse at the gain: %.3f mm %.4f deg; as they are: %.3f mm %.4f deg\n", on.mm,
              on.deg, off.mm, off.deg);
  // Measured 0.034 mm / 0.0007 deg at the gain, 0.436 mm / 0.0069 deg as they are.
  EXPECT_LT(on.mm, 1.3 * 0.034);
  EXPECT_LT(on.deg, 1.3 * 0.0007);
  EXPECT_GT(off.mm, 5.0 * on.mm);
  EXPECT_GT(off.deg, 5.0 * on.deg);
}

// A camera's auto exposure: b's colour is 0.8 times a's. At the gain the term measures (a's grey
// values over b's) it converges as on equal exposures; comparing the grey values as they are,
// every residual carries the difference and the motion is led off.
TEST(DirectTerms, PhotometricComparesGreyValuesAtTheMeasuredGain) {
  const Pair p = renderedPair(true, false, 0.8);
  const DirectImages ref = referenceImages(p.a);
  const DirectImages mov = directImages(p.b);
  auto at = [&](const Eigen::Isometry3d& T, bool gain) {
    return photometricSums(ref, mov, p.b, landings(ref, mov, p.b, T), gain);
  };
  const DirectSums measured = at(trueMotion(), true);
  std::printf("  gain measured at the true motion: %.4f (1 / 0.8 = 1.25)\n",
              measured.brightness.gain);
  EXPECT_NEAR(measured.brightness.gain, 1.25, 0.005);
  EXPECT_EQ(measured.brightness.vignetting, 0.0);  // not asked for
  EXPECT_EQ(at(trueMotion(), false).brightness.gain, 1.0);
  const Error on = errorOf(iterate([&](const auto& T) { return at(T, true); }, 8));
  const Error off = errorOf(iterate([&](const auto& T) { return at(T, false); }, 8));
  std::printf("  photometric at the gain: %.3f mm %.4f deg; as they are: %.3f mm %.4f deg\n",
              on.mm, on.deg, off.mm, off.deg);
  // Measured 0.034 mm / 0.0007 deg at the gain (equal exposures: 0.044 mm / 0.0013 deg) and
  // 0.295 mm / 0.0153 deg as they are; bounds 1.3x, and the gain at least 5x better.
  EXPECT_LT(on.mm, 1.3 * 0.034);
  EXPECT_LT(on.deg, 1.3 * 0.0007);
  EXPECT_GT(off.mm, 5.0 * on.mm);
  EXPECT_GT(off.deg, 5.0 * on.deg);
}

// A lens's vignetting, exp(-1 rho) in both images: a point that moves across the image changes
// its grey value by exp(-(rho(q) - rho(p))). The term measures it from the pairs, and converges
// with it as on a camera without (PhotometricAloneConvergesToTheTrueMotion's bounds). One pair
// moves points by up to 0.03 in rho, so what the model gains shows over a sequence
// (Sequences.VignettingIsMeasuredNotMistakenForMotion), not here.
TEST(DirectTerms, PhotometricMeasuresTheCamerasVignetting) {
  const Pair p = renderedPair(true, false, 1.0, -1.0);
  const DirectImages ref = referenceImages(p.a);
  const DirectImages mov = directImages(p.b);
  auto at = [&](const Eigen::Isometry3d& T) {
    return photometricSums(ref, mov, p.b, landings(ref, mov, p.b, T), true, true);
  };
  const DirectSums measured = at(trueMotion());
  std::printf("  at the true motion: gain %.4f, vignetting %.3f (rendered 1, -1)\n",
              measured.brightness.gain, measured.brightness.vignetting);
  // Measured 0.9996 and -0.946 (the pairs' shifts span 0.06; grey values are 8-bit).
  EXPECT_NEAR(measured.brightness.gain, 1.0, 0.005);
  EXPECT_NEAR(measured.brightness.vignetting, -1.0, 0.1);
  const Error e = errorOf(iterate([&](const auto& T) { return at(T); }, 8));
  std::printf("  photometric with the vignetting: %.3f mm %.4f deg\n", e.mm, e.deg);
  EXPECT_LT(e.mm, 0.06);  // measured 0.048 mm, 0.0009 deg
  EXPECT_LT(e.deg, 0.0017);
}

// The gain is the median ratio of the pairs that neither image saturates and that are not dark,
// the vignetting the least-absolute-deviations slope of their log ratio against the shift;
// too few pairs, or a gain no exposure gives, leave the grey values as they are.
TEST(DirectTerms, BrightnessIsMeasuredFromTheUsablePairs) {
  auto pair = [](float reference, float moving, float shift = 0.0f) {
    return GreyPair{reference, moving, shift, 1.0f};
  };
  std::vector<GreyPair> pairs;
  for (int k = 0; k < 100; ++k) pairs.push_back(pair(1.2f * float(20 + k), float(20 + k)));
  EXPECT_NEAR(brightnessOf(pairs, true, false).gain, 1.2, 1e-6);
  EXPECT_EQ(brightnessOf(pairs, false, false).gain, 1.0);  // asked for nothing
  // A third as many again see another surface: the median stays.
  for (int k = 0; k < 33; ++k) pairs.push_back(pair(240.0f, 30.0f));
  EXPECT_NEAR(brightnessOf(pairs, true, false).gain, 1.2, 1e-6);
  // Saturated in either image, or dark in either: left out, however many.
  std::vector<GreyPair> more = pairs;
  for (int k = 0; k < 300; ++k) {
    more.push_back(pair(255.0f, 100.0f));
    more.push_back(pair(100.0f, 250.0f));
    more.push_back(pair(30.0f, 5.0f));
    more.push_back(pair(5.0f, 30.0f));
  }
  EXPECT_NEAR(brightnessOf(more, true, false).gain, 1.2, 1e-6);
  // Fewer than kMinGainPairs usable pairs, or a gain beyond kMaxGain: 1.
  const std::vector<GreyPair> few(pairs.begin(), pairs.begin() + 29);
  EXPECT_EQ(brightnessOf(few, true, true).gain, 1.0);
  EXPECT_NEAR(brightnessOf({pairs.begin(), pairs.begin() + 30}, true, false).gain, 1.2, 1e-6);
  std::vector<GreyPair> dark;
  for (int k = 0; k < 100; ++k) dark.push_back(pair(float(20 + k), 2.5f * float(20 + k)));
  EXPECT_EQ(brightnessOf(dark, true, false).gain, 1.0);  // 0.4 < 1 / kMaxGain
  EXPECT_EQ(brightnessOf({}, true, true).gain, 1.0);

  // Vignetting -0.8 and gain 1.1: reference = 1.1 exp(-0.8 shift) moving, a fifth of the pairs
  // far off (another surface); shifts of either sign.
  std::vector<GreyPair> vignetted;
  for (int k = 0; k < 500; ++k) {
    const float shift = 0.002f * float(k % 41 - 20), moving = float(40 + k % 150);
    const bool outlier = k % 5 == 0;
    vignetted.push_back(
        pair(outlier ? 0.5f * moving : float(1.1 * std::exp(-0.8 * shift)) * moving, moving, shift));
  }
  const Brightness both = brightnessOf(vignetted, true, true);
  EXPECT_NEAR(both.gain, 1.1, 1e-3);
  EXPECT_NEAR(both.vignetting, -0.8, 1e-2);
  EXPECT_NEAR(both.at(0.02), 1.1 * std::exp(-0.8 * 0.02), 1e-3);
  // The vignetting alone (gain 1 assumed), and a slope beyond kMinVignetting clamped.
  EXPECT_EQ(brightnessOf(vignetted, false, true).gain, 1.0);
  std::vector<GreyPair> steep;
  for (int k = 0; k < 100; ++k) {
    const float shift = 0.01f * float(k % 11 - 5);
    steep.push_back(pair(float(100.0 * std::exp(-5.0 * shift)), 100.0f, shift));
  }
  EXPECT_EQ(brightnessOf(steep, false, true).vignetting, kMinVignetting);
  // No shift at all: nothing to measure a slope with.
  EXPECT_EQ(brightnessOf(pairs, true, true).vignetting, 0.0);
}

TEST(DirectTerms, PointToPlaneAloneConvergesOnExactDepth) {
  const Pair p = renderedPair(false, false);
  const DirectImages ref = referenceImages(p.a), mov = directImages(p.b);
  const Error e =
      errorOf(iterate([&](const auto& T) { return pointToPlaneAt(ref, mov, p.b, T, 0.0025); }, 8));
  std::printf("  point to plane: %.4f mm %.5f deg\n", e.mm, e.deg);
  // Measured 0.026 mm / 0.0010 deg: an untextured room's points sit on its edges, where few
  // keep a plane around them.
  EXPECT_LT(e.mm, 0.04);
  EXPECT_LT(e.deg, 0.0015);
}

TEST(DirectTerms, PointToPlaneFadesOutAsTheDepthNoiseReachesTheModelled) {
  const Pair exact = renderedPair(false, false), noisy = renderedPair(false, true);
  const DirectImages exact_ref = referenceImages(exact.a), noisy_ref = referenceImages(noisy.a);
  const DirectImages exact_b = directImages(exact.b), noisy_b = directImages(noisy.b);
  auto on_exact_depth = [&](double depth_noise) {
    return pointToPlaneAt(exact_ref, exact_b, exact.b, trueMotion(), depth_noise);
  };
  auto on_noisy_depth = [&](double depth_noise) {
    return pointToPlaneAt(noisy_ref, noisy_b, noisy.b, trueMotion(), depth_noise);
  };
  // depth_noise 0 declares the depth exact: full weight, 1 / scale^2.
  const DirectSums on_exact = on_exact_depth(0.0025), full_exact = on_exact_depth(0.0);
  const DirectSums on_noisy = on_noisy_depth(0.0025), full_noisy = on_noisy_depth(0.0);
  std::printf("  learned scale: exact depth %.2e, Kinect-like noise %.2e (1/m)\n", on_exact.scale,
              on_noisy.scale);
  // Noise bends the depth at many pixels: measured 259 of the points keep a plane around them.
  EXPECT_GT(on_noisy.used, 100);
  // Exact depth: the scale stops at its floor, 1e-5; rendered Kinect-like noise: measured
  // 8.0e-4, under the modelled sqrt(2) 0.0025 = 3.5e-3 (this renderer's noise is a Kinect's
  // at its best).
  EXPECT_LE(on_exact.scale, 1e-5);
  EXPECT_GT(on_noisy.scale, 5e-4);
  // The weight is 1 - scale / (kPlaneFade sqrt(2) depth_noise) of the full one.
  auto fade = [](const DirectSums& s, double depth_noise) {
    return 1.0 - s.scale / (kPlaneFade * std::sqrt(2.0) * depth_noise);
  };
  EXPECT_NEAR(on_exact.H.trace() / full_exact.H.trace(), fade(on_exact, 0.0025), 1e-9);
  EXPECT_NEAR(on_noisy.H.trace() / full_noisy.H.trace(), fade(on_noisy, 0.0025), 1e-9);
  EXPECT_GT(fade(on_exact, 0.0025), 0.99);
  // A model that claims less noise than the residuals show (0.001: half of its sqrt(2) 0.001 is
  // below the learned 8e-4) gives the term no weight.
  EXPECT_EQ(on_noisy_depth(0.001).H.trace(), 0.0);
}

// The grid's windows see the renderer's Kinect-like noise drawn per pixel as independent, drawn in
// 3-px blobs (a real structured-light camera's shape, scripts/depth_noise) as shared:
// the term is on for the first, off for the second; on exact depth it is on at full weight.
TEST(DirectTerms, DenseGridTellsNoisePerPixelFromNoiseInBlobs) {
  const LabelledCloud per_pixel = renderedPair(false, true).a;
  const LabelledCloud blobs = renderedPair(false, true, 1.0, 0.0, 3.0).a;
  const LabelledCloud exact = renderedPair(false, false).a;
  const DepthGrid g_pixel = denseGrid(per_pixel.depth, per_pixel.camera, kDepthNoise);
  const DepthGrid g_blobs = denseGrid(blobs.depth, blobs.camera, kDepthNoise);
  const DepthGrid g_exact = denseGrid(exact.depth, exact.camera, kDepthNoise);
  std::printf(
      "  independence / shared noise (1/m) / weight / points: per pixel %.3f %.2e %.3f %zu, "
      "blobs %.3f %.2e %.3f %zu, exact %.3f %.2e %.3f %zu\n",
      g_pixel.independence, g_pixel.shared_noise, g_pixel.weight, g_pixel.points.size(),
      g_blobs.independence, g_blobs.shared_noise, g_blobs.weight, g_blobs.points.size(),
      g_exact.independence, g_exact.shared_noise, g_exact.weight, g_exact.points.size());
  // Measured: per pixel 0.90; in blobs 0 (neighbours' quantised depths mostly equal: the
  // pixels' twist is 0 in more than 80% of the windows).
  EXPECT_GT(g_pixel.independence, 0.7);
  EXPECT_LT(g_blobs.independence, 0.2);
  EXPECT_NEAR(g_pixel.weight, g_pixel.independence, 1e-12);
  EXPECT_GT(g_pixel.points.size(), 2000u);
  // Blobs: the shared noise is the modelled one's order, so no weight and no points.
  EXPECT_GT(g_blobs.shared_noise, kPlaneFade * kDepthNoise);
  EXPECT_EQ(g_blobs.weight, 0.0);
  EXPECT_TRUE(g_blobs.empty());
  // Exact depth: only the 16-bit image's 0.2 mm steps, far under the modelled noise (measured
  // 4e-6, weight 0.997).
  EXPECT_LT(g_exact.shared_noise, 0.05 * kDepthNoise);
  EXPECT_GT(g_exact.weight, 0.95);
  EXPECT_GT(g_exact.points.size(), 2000u);
  // Points 5 px apart on exact depth, 10 px apart where there is noise to average; a last level
  // led by the depth (no modelled noise) keeps them 10 px apart whatever the depth.
  EXPECT_EQ(g_pixel.stride, kGridStride);
  EXPECT_EQ(g_exact.stride, kExactGridStride);
  EXPECT_GT(g_exact.points.size(), 3 * g_pixel.points.size());
  const DepthGrid g_exact_led = denseGrid(exact.depth, exact.camera, 0.0);
  EXPECT_EQ(g_exact_led.stride, kGridStride);
  EXPECT_GT(g_exact.points.size(), 3 * g_exact_led.points.size());
  // Depth of another instant than the colour: no grid, whatever its noise.
  LabelledCloud moved = per_pixel;
  moved.depth_of_another_instant = true;
  EXPECT_TRUE(directImages(moved, true, kDepthNoise).grid.empty());
  EXPECT_FALSE(directImages(per_pixel, true, kDepthNoise).grid.empty());
  EXPECT_TRUE(directImages(per_pixel, false, kDepthNoise).grid.empty());
}

// Depth with nothing to measure: no valid pixel, NaN everywhere, an image smaller than a window;
// and a flat wall at one depth, exact: full weight.
TEST(DirectTerms, DenseGridOfBlankOrTinyDepth) {
  const Camera camera;
  const cv::Mat nan(480, 640, CV_32FC1, cv::Scalar(std::nan("")));
  for (const cv::Mat& depth : {cv::Mat(cv::Mat::zeros(480, 640, CV_32FC1)), nan,
                               cv::Mat(cv::Mat(4, 4, CV_32FC1, cv::Scalar(2.0f)))}) {
    const DepthGrid g = denseGrid(depth, camera, kDepthNoise);
    EXPECT_TRUE(g.empty());
    EXPECT_EQ(g.weight, 0.0);
  }
  const DepthGrid wall = denseGrid(cv::Mat(480, 640, CV_32FC1, cv::Scalar(2.0f)), camera,
                                   kDepthNoise);
  EXPECT_EQ(wall.weight, 1.0);
  ASSERT_FALSE(wall.empty());
  for (const Eigen::Vector3d& p : wall.points) EXPECT_NEAR(p.z(), 2.0, 1e-6);
}

// The dense term alone converges to the true motion: on exact depth to a few hundredths of a
// millimetre, on noise per pixel to a fraction of the sparse term's error there.
TEST(DirectTerms, DensePlaneAloneConverges) {
  for (const bool noise : {false, true}) {
    const Pair p = renderedPair(false, noise);
    const DirectImages ref = denseReference(p.a), mov = directImages(p.b, true, kDepthNoise);
    ASSERT_FALSE(ref.point_sums.empty());
    const Error dense =
        errorOf(iterate([&](const auto& T) { return densePlaneSums(ref, mov, T); }, 8));
    // Noise bends the depth around most of the sparse points (PointToPlaneFades...: 259 keep a
    // plane).
    const Error sparse = errorOf(
        iterate([&](const auto& T) { return pointToPlaneAt(ref, mov, p.b, T, 0.0); }, 8, 100));
    std::printf("  %s: dense %.5f mm %.6f deg, sparse (full weight) %.4f mm %.5f deg\n",
                noise ? "noise per pixel" : "exact depth", dense.mm, dense.deg, sparse.mm,
                sparse.deg);
    if (!noise) {
      // Measured 0.00065 mm / 0.000028 deg with the grid's points 5 px apart (10 px: 0.0017 mm /
      // 0.00005 deg; the sparse term: 0.026 mm / 0.0010 deg).
      EXPECT_LT(dense.mm, 0.00085);
      EXPECT_LT(dense.deg, 0.000037);
    } else {
      // Measured 0.23 mm / 0.0078 deg against the sparse term's 2.8 mm / 0.089 deg.
      EXPECT_LT(dense.mm, 0.3);
      EXPECT_LT(dense.deg, 0.01);
      EXPECT_LT(dense.mm, 0.2 * sparse.mm);
      EXPECT_LT(dense.deg, 0.2 * sparse.deg);
    }
  }
}

// A 40x30 image: a wall at 2 m, its right half (columns 20-39) a box face at 1 m; random grey
// values (or flat ones), and points at the given pixels.
LabelledCloud wallAndBox(std::initializer_list<cv::Point> pixels, bool random_grey = true) {
  LabelledCloud c;
  c.width = 40;
  c.height = 30;
  c.camera = Camera{30.0, 30.0, 19.5, 14.5, 40, 30, 1.0};
  c.gray = cv::Mat(30, 40, CV_8UC1, cv::Scalar(100));
  if (random_grey) cv::randu(c.gray, 0, 255);
  c.depth = cv::Mat(30, 40, CV_32FC1, cv::Scalar(2.0f));
  c.depth.colRange(20, 40).setTo(1.0f);
  for (const cv::Point px : pixels) {
    c.pixels.push_back(px);
    c.points.push_back(c.camera.backProject(px.x, px.y, c.depth.at<float>(px)).cast<float>());
  }
  return c;
}

TEST(DirectTerms, PointsOnADepthEdgeOrOccludedAreLeftOut) {
  // Points inside the wall, beside the edge on either side, inside the box. Identity motion.
  const LabelledCloud c = wallAndBox(
      {cv::Point(10, 15), cv::Point(19, 15), cv::Point(20, 15), cv::Point(30, 15)});
  const DirectImages ref = referenceImages(c);
  const DirectImages mov = directImages(c);
  // The two points beside the edge are left out, the two inside each surface kept.
  EXPECT_EQ(photometricAt(ref, mov, c, Eigen::Isometry3d::Identity()).used, 2);
  EXPECT_EQ(pointToPlaneAt(ref, mov, c, Eigen::Isometry3d::Identity(), 0.0).used, 2);
  // Moved 0.5 m back, every point lands where the reference sees something else: occluded.
  const Eigen::Isometry3d back(Eigen::Translation3d(0.0, 0.0, 0.5));
  EXPECT_EQ(photometricAt(ref, mov, c, back).used, 0);
  EXPECT_EQ(pointToPlaneAt(ref, mov, c, back, 0.0).used, 0);
}

// The reverse direction by the same rules at the other end: a reference point is used where it
// lands on the moving depth's surface, one surface around the landing and along the moving
// image's blur.
TEST(DirectTerms, ReverseLandingsOnADepthEdgeOccludedOrBlurredOverOneAreLeftOut) {
  // Points 4 px left of the edge (on the wall), 4 px right of it (on the box), 10 px left of it
  // and inside the box.
  const LabelledCloud c = wallAndBox(
      {cv::Point(16, 15), cv::Point(24, 15), cv::Point(10, 15), cv::Point(30, 15)});
  const DirectImages ref = referenceImages(c);
  LabelledCloud moving = c;
  const Eigen::Isometry3d still = Eigen::Isometry3d::Identity();
  EXPECT_EQ(reverseAt(ref, c, directImages(moving, false, 0.0, true), moving, still).used, 4);
  // The moving camera 0.5 m forward: every point lands where the moving depth is 0.5 m behind
  // it (the same image, a surface the point is not on).
  const Eigen::Isometry3d forward(Eigen::Translation3d(0.0, 0.0, 0.5));
  EXPECT_EQ(reverseAt(ref, c, directImages(moving, false, 0.0, true), moving, forward).used, 0);
  // The moving image blurred sideways by 0.4 m: the landings 4 px either side of the edge smear
  // across it; the one 10 px away and the one inside the box do not.
  moving.blur_motion = Eigen::Translation3d(0.4, 0.0, 0.0) * Eigen::Isometry3d::Identity();
  EXPECT_EQ(reverseAt(ref, c, directImages(moving, false, 0.0, true), moving, still).used, 2);
  // A landing beside the edge (its 4 neighbours on both surfaces) is left out.
  const LabelledCloud beside = wallAndBox({cv::Point(19, 15), cv::Point(20, 15)});
  DirectImages beside_ref = referenceImages(beside);
  beside_ref.one_surface.assign(2, 1);  // as if the reference saw them inside a surface
  EXPECT_EQ(reverseAt(beside_ref, beside, directImages(c, false, 0.0, true), c, still).used, 0);
}

TEST(DirectTerms, PointsWhoseBlurCrossesADepthEdgeAreLeftOut) {
  // Points 4 px left of the edge (on the wall), 4 px right of it (on the box) and 10 px left of
  // it.
  LabelledCloud c = wallAndBox({cv::Point(16, 15), cv::Point(24, 15), cv::Point(10, 15)}, false);
  auto kept = [&c](const Eigen::Vector3d& shift) {
    c.blur_motion = Eigen::Translation3d(shift) * Eigen::Isometry3d::Identity();
    const DirectImages images = directImages(c);
    return std::vector<int>(images.one_surface.begin(), images.one_surface.end());
  };
  // No blur known: each point's 4-neighbours are one surface.
  EXPECT_EQ(kept(Eigen::Vector3d::Zero()), (std::vector<int>{1, 1, 1}));
  // Sideways by 0.4 m (wall points move 6 px, box points 12 px): each smear reaches half its
  // length and a pixel either side, so the wall point 4 px from the edge (3 + 1 px) and the
  // box point (6 + 1 px) cross it; the wall point 10 px away does not.
  EXPECT_EQ(kept(Eigen::Vector3d(0.4, 0.0, 0.0)), (std::vector<int>{0, 0, 1}));
  // Up and down by as much, along the edge: nothing crosses it.
  EXPECT_EQ(kept(Eigen::Vector3d(0.0, 0.4, 0.0)), (std::vector<int>{1, 1, 1}));
  // A smear of a pixel or less is within the 4-neighbours already checked.
  EXPECT_EQ(kept(Eigen::Vector3d(0.05, 0.0, 0.0)), (std::vector<int>{1, 1, 1}));
}

// The engine as the odometry runs it, with and without the direct terms, on rendered pairs.
TEST(DirectTerms, MakeTheDefaultEngineFinerThanItsKernel) {
  for (const bool texture : {true, false}) {
    const Pair p = renderedPair(texture, false);
    Error e[2];
    for (const bool direct : {false, true}) {
      CoarseToFineParams params;
      params.photometric = params.point_to_plane = params.dense_point_to_plane = direct;
      const auto A = prepareCoarseToFine(p.a, params, true);
      const auto B = prepareCoarseToFine(p.b, params, false);
      e[direct] =
          errorOf(alignCoarseToFine(*A, *B, Eigen::Isometry3d::Identity(), params).transform);
      std::printf("  %s room, direct terms %s: %.4f mm %.5f deg\n",
                  texture ? "textured" : "untextured", direct ? "on " : "off", e[direct].mm,
                  e[direct].deg);
    }
    // Measured, textured room: kernel 0.37 mm / 0.021 deg, with the terms 0.0003 mm /
    // 0.00001 deg; untextured: 1.34 mm / 0.052 deg, then 0.0027 mm / 0.00011 deg.
    EXPECT_LT(e[1].mm, 0.03);
    EXPECT_LT(e[1].deg, 0.0013);
    EXPECT_LT(e[1].mm, 0.05 * e[0].mm);
    EXPECT_LT(e[1].deg, 0.05 * e[0].deg);
  }
}

// The engine reports the dense term's weight: the moving grid's on noise per pixel, 0 on noise in
// blobs, NaN when the term is turned off.
TEST(DirectTerms, TheEngineReportsTheDenseTermsWeight) {
  auto weightOn = [](const Pair& p, bool dense) {
    CoarseToFineParams params;
    params.dense_point_to_plane = dense;
    const auto A = prepareCoarseToFine(p.a, params, true);
    const auto B = prepareCoarseToFine(p.b, params, false);
    const double w =
        alignCoarseToFine(*A, *B, Eigen::Isometry3d::Identity(), params).coarse_to_fine->dense_weight;
    if (dense) {
      EXPECT_EQ(w, B->images.grid.weight);
    }
    return w;
  };
  const Pair per_pixel = renderedPair(false, true);
  EXPECT_GT(weightOn(per_pixel, true), kMinIndependence);
  EXPECT_TRUE(std::isnan(weightOn(per_pixel, false)));
  EXPECT_EQ(weightOn(renderedPair(false, true, 1.0, 0.0, 3.0), true), 0.0);
}

// A last level led by the depth (CoarseToFineParams::depth_led, where the colour is from another
// camera): both plane terms count whatever the depth's noise, the dense term too on noise in
// blobs, which leaves it off by default; the kernel weighs kDepthLedKernelShare of its weight.
TEST(DirectTerms, ALastLevelLedByTheDepthCountsThePlaneTermsWhateverTheNoise) {
  const Pair blobs = renderedPair(false, true, 1.0, 0.0, 3.0);
  auto align = [&blobs](CoarseToFineParams params) {
    const auto A = prepareCoarseToFine(blobs.a, params, true);
    const auto B = prepareCoarseToFine(blobs.b, params, false);
    return alignCoarseToFine(*A, *B, Eigen::Isometry3d::Identity(), params);
  };
  CoarseToFineParams plain, led;
  plain.photometric = led.photometric = false;
  led.depth_led = true;
  EXPECT_EQ(planeFadeNoise(plain), plain.depth_noise);
  EXPECT_EQ(planeFadeNoise(led), 0.0);
  const SolverResult a = align(plain), b = align(led);
  EXPECT_EQ(a.coarse_to_fine->dense_weight, 0.0);
  EXPECT_EQ(b.coarse_to_fine->dense_weight, 1.0);
  std::printf("  untextured room, noise in blobs: %.4f mm %.5f deg; led by the depth: %.4f mm "
              "%.5f deg\n",
              errorOf(a.transform).mm, errorOf(a.transform).deg, errorOf(b.transform).mm,
              errorOf(b.transform).deg);
  // Measured 1.43 mm / 0.0560 deg, led by the depth 0.83 mm / 0.0297 deg: with the grey values
  // left out, the kernel alone leaves the flat-coloured room looser than the planes do.
  EXPECT_LT(errorOf(b.transform).mm, 1.2 * 0.834);
  EXPECT_LT(errorOf(b.transform).deg, 1.2 * 0.0297);
  EXPECT_LT(errorOf(b.transform).mm, 0.75 * errorOf(a.transform).mm);
  EXPECT_LT(errorOf(b.transform).deg, 0.75 * errorOf(a.transform).deg);
}

// The engine in two calls, the stages before the finest and then the finest from where they
// left off, registers as one call does (Odometry moves the depth again in between).
TEST(DirectTerms, TheEngineInTwoStagesIsTheEngineInOne) {
  const Pair p = renderedPair(true, true);
  const CoarseToFineParams params;
  const auto A = prepareCoarseToFine(p.a, params, true);
  const auto B = prepareCoarseToFine(p.b, params, false);
  const Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  const SolverResult whole = alignCoarseToFine(*A, *B, guess, params);
  const SolverResult coarse = alignCoarseToFine(*A, *B, guess, params, AlignStages::kCoarse);
  const SolverResult finest =
      alignCoarseToFine(*A, *B, coarse.transform, params, AlignStages::kFinest);
  const SolverResult both = combinedStages(coarse, finest);
  std::printf("  coarse levels %.4f mm %.5f deg, all %.4f mm %.5f deg\n",
              errorOf(coarse.transform).mm, errorOf(coarse.transform).deg,
              errorOf(whole.transform).mm, errorOf(whole.transform).deg);
  EXPECT_GT(coarse.iterations, 0);
  EXPECT_GT(finest.iterations, 0);
  // Measured: the coarse levels alone 1.63 mm / 0.059 deg, all of them 0.10 mm / 0.0029 deg.
  EXPECT_LT(errorOf(coarse.transform).mm, 2.5);
  EXPECT_GT(errorOf(coarse.transform).mm, 10.0 * errorOf(whole.transform).mm);
  EXPECT_TRUE(both.transform.isApprox(whole.transform, 1e-12));
  EXPECT_EQ(both.iterations, whole.iterations);
  EXPECT_EQ(both.trace.size(), whole.trace.size());
  EXPECT_EQ(both.nnz, whole.nnz);
  EXPECT_EQ(both.matched_fraction, whole.matched_fraction);
  EXPECT_EQ(both.status, whole.status);

  // One level only: nothing before the finest, the guess comes back.
  CoarseToFineParams one = params;
  one.ell_init = one.ell_min;
  const SolverResult none = alignCoarseToFine(*A, *B, trueMotion(), one, AlignStages::kCoarse);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_EQ(none.status, SolverStatus::kConverged);
  EXPECT_TRUE(none.transform.isApprox(trueMotion(), 1e-15));
}

}  // namespace
}  // namespace acvo
