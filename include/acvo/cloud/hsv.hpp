// OpenCV's 8-bit RGB -> HSV conversion for single pixels, so that a cloud converts only the
// pixels it keeps. Bit-exact with cv::cvtColor(..., cv::COLOR_RGB2HSV) (tested on all colours).
#pragma once

#include <array>
#include <cstdint>

namespace acvo {

// H in [0, 180) (degrees / 2), S and V in [0, 255].
std::array<std::uint8_t, 3> rgbToHsv(std::uint8_t r, std::uint8_t g, std::uint8_t b);

}  // namespace acvo
