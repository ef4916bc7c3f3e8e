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

// gray: CV_8UC1; depth: CV_32FC1 metres, 0 = invalid (same size). Deterministic for a given
// input. Pixels within 4 px of the border and pixels whose depth is invalid or outside
// [min_depth, max_depth] are never returned.
Selection selectPixels(const cv::Mat& gray, const cv::Mat& depth, const SelectionParams& params);

}  // namespace acvo
