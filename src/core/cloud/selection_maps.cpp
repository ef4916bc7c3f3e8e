// Choices the method leaves open, made here: the block median is the value of rank floor(n/2)
// among the block's n pixels that have central differences; the 3x3 smoothing averages the
// neighbouring blocks that exist (fewer at the image edges); blocks at the right and bottom edges
// may be partial.
#include "selection_maps.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace acvo::selection {
namespace {

constexpr int kBlock = 32;          // side of the blocks the thresholds are computed on
constexpr int kHistMax = 48;        // floor(|grad I|) is clamped to this in the histogram
constexpr float kThresholdAdd = 7;  // added to the block median
constexpr std::array<float, 3> kLevelFactor = {1.f, 0.75f, 0.75f * 0.5625f};

using Histogram = std::array<int, kHistMax + 1>;

// |grad I|^2 by central differences into `out` (same size), 0 on the outermost pixels.
template <typename T>
void gradientMag2Into(const T* image, int width, int height, std::vector<float>& out) {
  out.assign(static_cast<std::size_t>(width) * height, 0.f);
  for (int v = 1; v + 1 < height; ++v) {
    const T* row = image + static_cast<std::size_t>(v) * width;
    const T* up = row - width;
    const T* down = row + width;
    float* o = out.data() + static_cast<std::size_t>(v) * width;
    for (int u = 1; u + 1 < width; ++u) {
      const float gx = 0.5f * (static_cast<float>(row[u + 1]) - static_cast<float>(row[u - 1]));
      const float gy = 0.5f * (static_cast<float>(down[u]) - static_cast<float>(up[u]));
      o[u] = gx * gx + gy * gy;
    }
  }
}

// 2x2 mean: the next pyramid level.
template <typename T>
std::vector<float> halve(const T* image, int width, int height) {
  const int w = width / 2, h = height / 2;
  std::vector<float> out(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    const T* r0 = image + static_cast<std::size_t>(2 * y) * width;
    const T* r1 = r0 + width;
    float* o = out.data() + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      o[x] = 0.25f * (static_cast<float>(r0[2 * x]) + static_cast<float>(r0[2 * x + 1]) +
                      static_cast<float>(r1[2 * x]) + static_cast<float>(r1[2 * x + 1]));
    }
  }
  return out;
}

int histogramBin(float mag2) {
  return std::min(static_cast<int>(std::sqrt(mag2)), kHistMax);
}

// Smoothed block thresholds on |grad I| (not squared), row-major over the blocks.
struct BlockThresholds {
  int blocks_x = 0;
  std::vector<float> th;
  float at(int bx, int by) const { return th[static_cast<std::size_t>(by) * blocks_x + bx]; }
};

// histogramBin(m) = binOfQuarters(floor(4 m)) for every m >= 0 (k^2 <= m if and only if
// 4 k^2 <= floor(4 m)), by table up to the last bin's 4 * 48^2. Level-0 values are quarters of
// integers anyway (central differences of 8-bit values).
constexpr int kLastQuarters = 4 * kHistMax * kHistMax;
const std::array<std::uint8_t, kLastQuarters + 1>& binOfQuarters() {
  static const auto table = [] {
    std::array<std::uint8_t, kLastQuarters + 1> t{};
    for (int q = 0; q <= kLastQuarters; ++q) {
      t[static_cast<std::size_t>(q)] = static_cast<std::uint8_t>(histogramBin(0.25f * q));
    }
    return t;
  }();
  return table;
}

BlockThresholds blockThresholds(const CandidateLevel& mag2) {
  const int bx = (mag2.width + kBlock - 1) / kBlock, by = (mag2.height + kBlock - 1) / kBlock;
  std::vector<Histogram> hist(static_cast<std::size_t>(bx) * by, Histogram{});
  // Per block row, four histograms per block that take the pixels in turn: neighbouring pixels
  // mostly fall in the same bin, and with one histogram each increment waited on the one before
  // (two thirds of the candidate maps' time went to that chain).
  const auto& bin_of = binOfQuarters();
  std::vector<std::array<Histogram, 4>> lanes(static_cast<std::size_t>(bx));
  std::vector<int> quarters(static_cast<std::size_t>(mag2.width), 0);
  for (int b = 0; b < by; ++b) {
    for (auto& l : lanes) l.fill(Histogram{});
    const int v_end = std::min((b + 1) * kBlock, mag2.height - 1);
    for (int v = std::max(b * kBlock, 1); v < v_end; ++v) {
      const float* row = &mag2.value[static_cast<std::size_t>(v) * mag2.width];
      for (int u = 1; u + 1 < mag2.width; ++u) {
        quarters[std::size_t(u)] = std::min(static_cast<int>(4.f * row[u]), kLastQuarters);
      }
      for (int u = 1; u + 1 < mag2.width; ++u) {
        ++lanes[std::size_t(u / kBlock)][std::size_t(u & 3)]
               [bin_of[std::size_t(quarters[std::size_t(u)])]];
      }
    }
    for (int x = 0; x < bx; ++x) {
      Histogram& h = hist[static_cast<std::size_t>(b) * bx + x];
      for (const Histogram& l : lanes[std::size_t(x)]) {
        for (std::size_t k = 0; k < h.size(); ++k) h[k] += l[k];
      }
    }
  }
  std::vector<float> median(hist.size());
  for (std::size_t b = 0; b < hist.size(); ++b) {
    int n = 0;
    for (int c : hist[b]) n += c;
    int bin = 0, below = 0;
    while (bin < kHistMax && below + hist[b][bin] <= n / 2) below += hist[b][bin++];
    median[b] = static_cast<float>(bin);
  }
  BlockThresholds out{bx, std::vector<float>(hist.size())};
  for (int y = 0; y < by; ++y) {
    for (int x = 0; x < bx; ++x) {
      float sum = 0.f;
      int num = 0;
      for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, by - 1); ++ny) {
        for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, bx - 1); ++nx) {
          sum += median[static_cast<std::size_t>(ny) * bx + nx] + kThresholdAdd;
          ++num;
        }
      }
      out.th[static_cast<std::size_t>(y) * bx + x] = sum / static_cast<float>(num);
    }
  }
  return out;
}

// Zeroes the values of level k at or below factor_k * th^2 of their block. A pixel of level k
// (scale s = 2^k) lies in the block of its level-0 footprint, as s divides the block side.
void keepAboveThreshold(CandidateLevel& level, int k, const BlockThresholds& th) {
  const int block = kBlock >> k;
  for (int y = 0; y < level.height; ++y) {
    float* row = &level.value[static_cast<std::size_t>(y) * level.width];
    for (int x0 = 0; x0 < level.width; x0 += block) {
      const float t = th.at(x0 / block, y / block);
      const float limit = kLevelFactor[k] * t * t;
      const int x1 = std::min(x0 + block, level.width);
      for (int x = x0; x < x1; ++x) row[x] = row[x] > limit ? row[x] : 0.f;
    }
  }
}

}  // namespace

CandidatePyramid candidateMaps(const cv::Mat& gray) {
  const cv::Mat g = gray.isContinuous() ? gray : gray.clone();
  const int w = g.cols, h = g.rows;
  const auto* i0 = g.ptr<std::uint8_t>();
  const std::vector<float> i1 = halve(i0, w, h);
  const std::vector<float> i2 = halve(i1.data(), w / 2, h / 2);

  CandidatePyramid pyr;
  pyr[0] = {w, h, {}};
  pyr[1] = {w / 2, h / 2, {}};
  pyr[2] = {w / 4, h / 4, {}};
  gradientMag2Into(i0, w, h, pyr[0].value);
  gradientMag2Into(i1.data(), w / 2, h / 2, pyr[1].value);
  gradientMag2Into(i2.data(), w / 4, h / 4, pyr[2].value);
  const BlockThresholds th = blockThresholds(pyr[0]);
  for (int k = 0; k < 3; ++k) keepAboveThreshold(pyr[k], k, th);
  return pyr;
}

float gradientMag2(const cv::Mat& gray, int u, int v) {
  const float gx = 0.5f * (static_cast<float>(gray.at<std::uint8_t>(v, u + 1)) -
                           static_cast<float>(gray.at<std::uint8_t>(v, u - 1)));
  const float gy = 0.5f * (static_cast<float>(gray.at<std::uint8_t>(v + 1, u)) -
                           static_cast<float>(gray.at<std::uint8_t>(v - 1, u)));
  return gx * gx + gy * gy;
}

}  // namespace acvo::selection
