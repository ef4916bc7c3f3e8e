// The candidate maps of the DSO-style selector (docs/method.md §1): for each level of a 3-level
// pyramid, |grad I|^2 where it exceeds that level's share of the local threshold, 0 elsewhere.
// Internal to point_selector.cpp (and its tests).
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace acvo::selection {

struct CandidateLevel {
  int width = 0, height = 0;
  std::vector<float> value;  // row-major; |grad I|^2 above the threshold, else 0
  float at(int u, int v) const { return value[static_cast<std::size_t>(v) * width + u]; }
};

// Level k has scale 2^k (2x2 means of the level below, odd last rows and columns dropped).
using CandidatePyramid = std::array<CandidateLevel, 3>;

// gray: CV_8UC1. Thresholds: per 32x32 block, the median of floor(|grad I|) (clamped to 48)
// plus 7, averaged over the 3x3 neighbouring blocks that have gradients, squared; level 1 uses
// 0.75 of it and level 2 0.75 * 0.5625. Gradients are central differences of each level; the
// outermost pixels of each level have none (value 0).
CandidatePyramid candidateMaps(const cv::Mat& gray);

// Picks of the selector's pass with cells of `pot` pixels over `gray` (point_selector.cpp), and
// their number for cells of one pixel counted by rows, as the selector counts its first pass:
// equal by construction, and tested to be.
std::size_t passSize(const cv::Mat& gray, int pot);
std::size_t densePassCount(const cv::Mat& gray);

// Level-0 |grad I|^2 at an inner pixel (1 <= u < cols - 1, 1 <= v < rows - 1).
float gradientMag2(const cv::Mat& gray, int u, int v);

}  // namespace acvo::selection
