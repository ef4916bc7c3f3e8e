// OpenCV's 8-bit HSV for single pixels: a cloud converts only its selected pixels.
#include "acvo/cloud/hsv.hpp"

#include <algorithm>
#include <cmath>

namespace acvo {
namespace {

// OpenCV's fixed-point scheme: divisions by V and by (max - min) are replaced by rounded
// reciprocals scaled by 2^12, and the products are rounded back.
constexpr int kShift = 12;

struct Reciprocals {
  std::array<int, 256> saturation{};  // round(255 * 2^12 / v)
  std::array<int, 256> hue{};         // round(180 * 2^12 / (6 diff))
  Reciprocals() {
    // Index 0 is never multiplied by anything but 0 (v = 0 -> diff = 0; diff = 0 -> h = 0).
    saturation[0] = hue[0] = 0;
    for (int i = 1; i < 256; ++i) {
      saturation[i] = static_cast<int>(std::lround((255 << kShift) / static_cast<double>(i)));
      hue[i] = static_cast<int>(std::lround((180 << kShift) / (6.0 * i)));
    }
  }
};

const Reciprocals& reciprocals() {
  static const Reciprocals table;
  return table;
}

}  // namespace

std::array<std::uint8_t, 3> rgbToHsv(std::uint8_t r8, std::uint8_t g8, std::uint8_t b8) {
  const Reciprocals& t = reciprocals();
  const int r = r8, g = g8, b = b8;
  const int v = std::max({r, g, b});
  const int diff = v - std::min({r, g, b});
  const int s = (diff * t.saturation[v] + (1 << (kShift - 1))) >> kShift;
  // Hue in sixths of the circle before scaling: which channel is the maximum picks the sector
  // (red first, then green, as OpenCV breaks ties).
  int h = v == r ? g - b : v == g ? b - r + 2 * diff : r - g + 4 * diff;
  h = (h * t.hue[diff] + (1 << (kShift - 1))) >> kShift;
  if (h < 0) h += 180;
  return {static_cast<std::uint8_t>(h), static_cast<std::uint8_t>(s), static_cast<std::uint8_t>(v)};
}

}  // namespace acvo
