// DSO-style semi-dense pixel selection with a Canny fallback (docs/method.md §1).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "acvo/params.hpp"

namespace acvo {

struct Selection {
  std::vector<cv::Point> pixels;  // selected pixels with valid depth, row-major order
  int cell_size = 0;              // final pot
  int gradient_pixels = 0;        // picked by the gradient selector (before the depth check)
  int canny_pixels = 0;           // added by the Canny fallback (before the depth check)
  bool canny_used = false;
};

// The depths a selected pixel may have: valid (0 and NaN are not) and within [min_depth,
// max_depth].
struct SelectableDepth {
  explicit SelectableDepth(const SelectionParams& p)
      : min(static_cast<float>(p.min_depth)), max(static_cast<float>(p.max_depth)) {}
  // NaN fails every comparison.
  bool operator()(float d) const { return d > 0.f && d >= min && d <= max; }
  float min, max;
};

// The number of points the selector aims at in an image of `size`: target_points, scaled by
// the image's size when scale_with_image (at least 1 point).
int targetPoints(const SelectionParams& params, cv::Size size);

// gray: CV_8UC1; depth: CV_32FC1 metres, 0 = invalid (same size). Deterministic for a given
// input. Aims at targetPoints(params, gray.size()) pixels. Pixels within 4 px of the border and
// pixels whose depth is invalid or outside [min_depth, max_depth] are never returned.
Selection selectPixels(const cv::Mat& gray, const cv::Mat& depth, const SelectionParams& params);

}  // namespace acvo
