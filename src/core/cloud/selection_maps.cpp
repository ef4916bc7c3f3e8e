// Choices the method leaves open, made here: the block median is the value of rank floor(n/2)
// among the block's n pixels that have central differences; the 3x3 smoothing averages the
// neighbouring blocks that exist and have such pixels (fewer at the image edges); blocks at the
// right and bottom edges may be partial.
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

// Smoothed block thresholds on |grad I| (not squared), row-major over the blocks.
struct BlockThresholds {
  int blocks_x = 0;
  std::vector<float> th;
  float at(int bx, int by) const { return th[static_cast<std::size_t>(by) * blocks_x + bx]; }
};

// How many of a block's bins are at most b (bins of pixels without gradient are kNoBin): per
// column of the block, in bytes (a block has at most kBlock rows), which vectorise.
constexpr std::uint8_t kNoBin = 255;
int countAtMost(const std::uint8_t* rows, int stride, int row_count, int u0, int u1,
                std::uint8_t b) {
  std::array<std::uint8_t, kBlock> per_column{};
  const int width = u1 - u0;
  for (int r = 0; r < row_count; ++r) {
    const std::uint8_t* row = rows + static_cast<std::size_t>(r) * stride + u0;
    for (int u = 0; u < width; ++u) {
      per_column[std::size_t(u)] =
          static_cast<std::uint8_t>(per_column[std::size_t(u)] + (row[u] <= b));
    }
  }
  int count = 0;
  for (const std::uint8_t c : per_column) count += c;
  return count;
}

// The bins of rows [v0, v1) of mag2 (into `bins`, row v at v - v0): each pixel's floor(|grad I|),
// clamped to kHistMax, as a byte (the square root vectorised, through `root`).
void binRows(const CandidateLevel& mag2, int v0, int v1, std::vector<float>& root,
             std::vector<std::uint8_t>& bins) {
  const int w = mag2.width;
  for (int v = v0; v < v1; ++v) {
    const float* row = &mag2.value[static_cast<std::size_t>(v) * w];
    std::uint8_t* out = &bins[static_cast<std::size_t>(v - v0) * w];
    for (int u = 1; u + 1 < w; ++u) root[std::size_t(u)] = std::sqrt(row[u]);
    for (int u = 1; u + 1 < w; ++u) {
      out[u] =
          static_cast<std::uint8_t>(std::min(static_cast<int>(root[std::size_t(u)]), kHistMax));
    }
  }
}

// The median bin of the block of columns [u0, u1) of the `row_count` binned rows (stride w): the
// first bin whose cumulative count exceeds half the block's pixels (kHistMax at most), by
// bisection over [0, kHistMax].
int medianBin(const std::vector<std::uint8_t>& bins, int w, int row_count, int u0, int u1) {
  const int half = row_count * (u1 - u0) / 2;
  int lo = 0, hi = kHistMax;
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (countAtMost(bins.data(), w, row_count, u0, u1, std::uint8_t(mid)) > half) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  return lo;
}

BlockThresholds blockThresholds(const CandidateLevel& mag2) {
  const int w = mag2.width, h = mag2.height;
  const int bx = (w + kBlock - 1) / kBlock, by = (h + kBlock - 1) / kBlock;
  // Per block row, each pixel's bin floor(|grad I|), clamped to kHistMax, as a byte (the square
  // root vectorised); then each block's median bin by bisection over [0, kHistMax], counting the
  // bins at most the middle one a block at a time. A histogram per block took its scattered
  // increments one by one: half the candidate maps' time.
  std::vector<std::uint8_t> bins(static_cast<std::size_t>(kBlock) * w, kNoBin);
  std::vector<float> root(static_cast<std::size_t>(w), 0.f);
  std::vector<float> median(static_cast<std::size_t>(bx) * by, 0.f);
  std::vector<std::uint8_t> has_pixels(median.size(), 0);
  for (int b = 0; b < by; ++b) {
    const int v0 = std::max(b * kBlock, 1), v1 = std::min((b + 1) * kBlock, h - 1);
    if (v0 >= v1) continue;
    binRows(mag2, v0, v1, root, bins);
    for (int a = 0; a < bx; ++a) {
      const int u0 = std::max(a * kBlock, 1), u1 = std::min((a + 1) * kBlock, w - 1);
      if (u0 >= u1) continue;
      const int lo = medianBin(bins, w, v1 - v0, u0, u1);
      median[static_cast<std::size_t>(b) * bx + a] = static_cast<float>(lo);
      has_pixels[static_cast<std::size_t>(b) * bx + a] = 1;
    }
  }
  // The mean over the 3x3 neighbouring blocks that have pixels (a block at the right or bottom
  // edge may hold only the outermost pixels, which have no gradient).
  BlockThresholds out{bx, std::vector<float>(median.size(), 0.f)};
  for (int y = 0; y < by; ++y) {
    for (int x = 0; x < bx; ++x) {
      float sum = 0.f;
      int num = 0;
      for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, by - 1); ++ny) {
        for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, bx - 1); ++nx) {
          const std::size_t k = static_cast<std::size_t>(ny) * bx + nx;
          if (!has_pixels[k]) continue;
          sum += median[k] + kThresholdAdd;
          ++num;
        }
      }
      out.th[static_cast<std::size_t>(y) * bx + x] = num > 0 ? sum / static_cast<float>(num) : 0.f;
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
