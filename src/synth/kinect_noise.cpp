#include "synth/kinect_noise.hpp"

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "synth/random.hpp"

namespace acvo::synth {
namespace {

// Streams of the per-row generators, so depth and colour noise of one frame are independent.
constexpr std::uint64_t kDepthStream = 0x4445505448ull;
constexpr std::uint64_t kColourStream = 0x434f4c4f5552ull;

bool atDiscontinuity(const cv::Mat& exact, int u, int v, float z, double jump) {
  for (int dv = -1; dv <= 1; ++dv) {
    const int y = v + dv;
    if (y < 0 || y >= exact.rows) continue;
    const float* row = exact.ptr<float>(y);
    for (int du = -1; du <= 1; ++du) {
      const int x = u + du;
      if (x < 0 || x >= exact.cols) continue;
      const float n = row[x];
      if (n <= 0.0f || std::abs(n - z) > jump) return true;
    }
  }
  return false;
}

}  // namespace

cv::Mat degradeDepth(const cv::Mat& exact, const KinectNoise& noise, double depth_scale,
                     std::uint64_t seed) {
  CV_Assert(exact.type() == CV_32FC1);
  cv::Mat out(exact.size(), CV_32FC1, cv::Scalar(0));
  const std::uint64_t stream = hashCombine(seed, kDepthStream);
  tbb::parallel_for(tbb::blocked_range<int>(0, exact.rows), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v < r.end(); ++v) {
      Rng rng(hashCombine(stream, v));
      const float* in = exact.ptr<float>(v);
      float* o = out.ptr<float>(v);
      for (int u = 0; u < exact.cols; ++u) {
        const double gaussian = rng.pixelNoise();  // drawn for every pixel: fixed stream layout
        const float z = in[u];
        if (!(z > 0.0f)) continue;
        const double jump = noise.edge_jump_base + noise.edge_jump_quadratic * z * z;
        if (atDiscontinuity(exact, u, v, z, jump)) continue;
        double measured = z + noise.depthSigma(z) * gaussian;
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
      for (int i = 0; i < 3 * colour.cols; ++i) p[i] += static_cast<float>(sigma * rng.pixelNoise());
    }
  });
}

}  // namespace acvo::synth
