#include "synth/kinect_noise.hpp"

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "synth/random.hpp"

namespace acvo::synth {
namespace {

// Streams of the per-row generators, so depth and colour noise of one frame are independent.
constexpr std::uint64_t kDepthStream = 0x4445505448ull;
constexpr std::uint64_t kColourStream = 0x434f4c4f5552ull;
constexpr std::uint64_t kFieldStream = 0x4649454c44ull;

// Unit-variance Gaussian noise correlated over `length` pixels: white noise (per-row
// generators, as the rest) smoothed by a Gaussian of that standard deviation, divided by the
// smoothing's own reduction of the standard deviation (the sum of the squared 1-D weights, for a
// separable kernel; the reflected border keeps each sum of weights 1).
cv::Mat correlatedField(cv::Size size, double length, std::uint64_t stream) {
  cv::Mat field(size, CV_32FC1);
  tbb::parallel_for(tbb::blocked_range<int>(0, size.height), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v < r.end(); ++v) {
      Rng rng(hashCombine(stream, v));
      float* f = field.ptr<float>(v);
      for (int u = 0; u < size.width; ++u) f[u] = static_cast<float>(rng.pixelNoise());
    }
  });
  const int taps = 2 * int(std::ceil(3.0 * length)) + 1;
  const cv::Mat kernel = cv::getGaussianKernel(taps, length, CV_64F);
  cv::sepFilter2D(field, field, CV_32F, kernel, kernel, {-1, -1}, 0.0, cv::BORDER_REFLECT_101);
  return field / kernel.dot(kernel);
}

}  // namespace

cv::Mat distortionField(cv::Size size, std::uint64_t seed) {
  // Drawn at an eighth of the size, correlated over an eighth of that width (an eighth of the
  // image's), then resized: the same smooth field at a fraction of the filtering's cost.
  const cv::Size small((size.width + 7) / 8, (size.height + 7) / 8);
  cv::Mat field = correlatedField(small, small.width / 8.0, seed);
  cv::resize(field, field, size, 0.0, 0.0, cv::INTER_CUBIC);
  cv::Scalar mean, stddev;
  cv::meanStdDev(field, mean, stddev);
  return (field - mean[0]) / stddev[0];
}

cv::Mat degradeDepth(const cv::Mat& exact, const KinectNoise& noise, double depth_scale,
                     std::uint64_t seed) {
  CV_Assert(exact.type() == CV_32FC1);
  cv::Mat out(exact.size(), CV_32FC1, cv::Scalar(0));
  // Extremes of each 3x3 neighbourhood (replicated border: only pixels in the image count),
  // to find discontinuities: a neighbour without depth, or one farther than the jump.
  cv::Mat lowest, highest;
  const cv::Mat box = cv::Mat::ones(3, 3, CV_8U);
  cv::erode(exact, lowest, box, {-1, -1}, 1, cv::BORDER_REPLICATE);
  cv::dilate(exact, highest, box, {-1, -1}, 1, cv::BORDER_REPLICATE);
  const std::uint64_t stream = hashCombine(seed, kDepthStream);
  const cv::Mat field =
      noise.correlation_px > 0.0
          ? correlatedField(exact.size(), noise.correlation_px, hashCombine(seed, kFieldStream))
          : cv::Mat();
  const cv::Mat distortion = noise.distortion_relative > 0.0
                                 ? distortionField(exact.size(), noise.distortion_seed)
                                 : cv::Mat();
  tbb::parallel_for(tbb::blocked_range<int>(0, exact.rows), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v < r.end(); ++v) {
      Rng rng(hashCombine(stream, v));
      const float* distorted = distortion.empty() ? nullptr : distortion.ptr<float>(v);
      const float* in = exact.ptr<float>(v);
      const float* lo = lowest.ptr<float>(v);
      const float* hi = highest.ptr<float>(v);
      float* o = out.ptr<float>(v);
      const float* correlated = field.empty() ? nullptr : field.ptr<float>(v);
      for (int u = 0; u < exact.cols; ++u) {
        double gaussian = rng.pixelNoise();  // drawn for every pixel: fixed stream layout
        if (correlated) gaussian = correlated[u];
        const float z = in[u];
        if (!(z > 0.0f)) continue;
        const double jump = noise.edge_jump_base + noise.edge_jump_quadratic * z * z;
        if (!(lo[u] > 0.0f) || hi[u] - z > jump || z - lo[u] > jump) continue;
        double measured = z + noise.depthSigma(z) * gaussian;
        if (distorted) measured *= 1.0 + noise.distortion_relative * distorted[u];
        if (measured <= 0.0) continue;
        if (noise.disparity_step > 0.0) {
          const double steps = std::round(noise.focal_baseline / measured / noise.disparity_step);
          if (steps < 1.0) continue;  // beyond the farthest representable depth
          measured = noise.focal_baseline / (steps * noise.disparity_step);
        }
        if (measured < noise.min_depth || measured > noise.max_depth) continue;
        // Integer depth images (16-bit PNG, millimetres) store multiples of 1 / depth_scale.
        if (depth_scale > 1.0) measured = std::round(measured * depth_scale) / depth_scale;
        o[u] = static_cast<float>(measured);
      }
    }
  });
  return out;
}

void addColourNoise(cv::Mat& colour, double sigma, std::uint64_t seed) {
  CV_Assert(colour.type() == CV_32FC3);
  if (sigma <= 0.0) return;
  const std::uint64_t stream = hashCombine(seed, kColourStream);
  tbb::parallel_for(tbb::blocked_range<int>(0, colour.rows), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v < r.end(); ++v) {
      Rng rng(hashCombine(stream, v));
      float* p = colour.ptr<float>(v);
      for (int i = 0; i < 3 * colour.cols; ++i)
        p[i] += static_cast<float>(sigma * rng.pixelNoise());
    }
  });
}

}  // namespace acvo::synth
