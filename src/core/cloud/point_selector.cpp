// DSO-style semi-dense selection (docs/method.md §1).
//
// Reading order: candidate maps (selection_maps.cpp) -> one selection pass for a cell size `pot`
// -> adapting pot to the target count -> Canny fallback -> depth check.
//
// Choices the method leaves open, made here:
// - A level-1 or level-2 pick is mapped back to the level-0 pixel with the largest level-0
//   |grad I|^2 inside that coarse pixel (first in row-major order on ties), so that the point
//   lands on the edge itself rather than on the coarse pixel's corner.
// - The target count applies before the depth check (as in the reference code): on Kinect
//   frames about 14 % of the selected pixels have no valid depth and are dropped afterwards.
#include "acvo/cloud/point_selector.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "selection_maps.hpp"

namespace acvo {
namespace {

using selection::CandidateLevel;
using selection::CandidatePyramid;

constexpr int kBorder = 4;  // pixels this close to the image edge are never selected
constexpr int kCannyBlock = 8;

// A half-open pixel rectangle [x0, x1) x [y0, y1).
struct Rect {
  int x0, y0, x1, y1;
  Rect clip(const Rect& r) const {
    return {std::max(x0, r.x0), std::max(y0, r.y0), std::min(x1, r.x1), std::min(y1, r.y1)};
  }
  bool empty() const { return x0 >= x1 || y0 >= y1; }
};

// Index (in `level`) of the largest candidate in `r`, or -1 when all are 0. Ties keep the first
// pixel in row-major order.
int bestCandidate(const CandidateLevel& level, const Rect& r) {
  int best = -1;
  float best_val = 0.f;
  for (int v = r.y0; v < r.y1; ++v) {
    const float* c = &level.value[static_cast<std::size_t>(v) * level.width];
    for (int u = r.x0; u < r.x1; ++u) {
      if (c[u] > best_val) {
        best_val = c[u];
        best = v * level.width + u;
      }
    }
  }
  return best;
}

// Index of the level-0 pixel in the non-empty `r` with the largest |grad I|^2 (first on ties).
int argmaxGradient(const cv::Mat& gray, const Rect& r) {
  int best = r.y0 * gray.cols + r.x0;
  float best_val = -1.f;
  for (int v = r.y0; v < r.y1; ++v) {
    for (int u = r.x0; u < r.x1; ++u) {
      const float val = selection::gradientMag2(gray, u, v);
      if (val > best_val) {
        best_val = val;
        best = v * gray.cols + u;
      }
    }
  }
  return best;
}

// The image and its candidate maps, as one selection pass reads them.
struct Maps {
  const cv::Mat& gray;
  const CandidatePyramid& pyr;
  Rect interior;
};

// The pixels of level k (scale s = 2^k) whose level-0 footprint meets the interior: coarse
// pixel x covers level-0 columns [x s, x s + s), so it meets the interior when x >= x0 / s and
// x s < x1. (Shifts: the coordinates are not negative, and a division by a variable s made this
// the costliest part of a pass.)
Rect coarseInterior(const Maps& m, int k) {
  const CandidateLevel& level = m.pyr[k];
  const int s = 1 << k;
  const Rect& in = m.interior;
  return Rect{in.x0 >> k, in.y0 >> k, (in.x1 + s - 1) >> k, (in.y1 + s - 1) >> k}.clip(
      {0, 0, level.width, level.height});
}

// Best candidate of level k whose level-0 footprint meets the interior, inside the level-0
// rectangle `cell` (its corners are multiples of 2^k): its index in level k, -1 when there is
// none.
int bestCoarse(const Maps& m, int k, const Rect& cell) {
  const Rect coarse =
      Rect{cell.x0 >> k, cell.y0 >> k, cell.x1 >> k, cell.y1 >> k}.clip(coarseInterior(m, k));
  return coarse.empty() ? -1 : bestCandidate(m.pyr[k], coarse);
}

// A coarse pick mapped back to the level-0 pixel of its footprint with the largest gradient.
int toLevel0(const Maps& m, int k, int coarse_index) {
  const int s = 1 << k, width = m.pyr[k].width;
  const int x = coarse_index % width, y = coarse_index / width;
  return argmaxGradient(m.gray, Rect{x * s, y * s, x * s + s, y * s + s}.clip(m.interior));
}

// A pass's picks: level-0 pixels, and coarse ones as (level, index in it), mapped back to level
// 0 only for the pass that is kept (the first pass often serves only to count).
struct PassPicks {
  std::vector<int> pixels;
  std::vector<std::pair<int, int>> coarse;
  std::size_t size() const { return pixels.size() + coarse.size(); }
};

std::vector<int> level0Pixels(const Maps& m, PassPicks pass) {
  std::vector<int> out = std::move(pass.pixels);
  out.reserve(out.size() + pass.coarse.size());
  for (const auto& [k, index] : pass.coarse) out.push_back(toLevel0(m, k, index));
  return out;
}

// bestCandidate in the cell of pot x pot pixels at (x, y), clipped to the interior; a cell of one
// pixel (the first, dense pass) without the rectangle's arithmetic.
int bestInCell(const CandidateLevel& g0, const Rect& interior, int x, int y, int pot) {
  if (pot == 1) {
    const bool inside = x >= interior.x0 && x < interior.x1 && y >= interior.y0 && y < interior.y1;
    const int index = y * g0.width + x;
    return inside && g0.value[static_cast<std::size_t>(index)] > 0.f ? index : -1;
  }
  const Rect cell = Rect{x, y, x + pot, y + pot}.clip(interior);
  return cell.empty() ? -1 : bestCandidate(g0, cell);
}

// One pass over cells of pot x pot pixels, nested as DSO does: a 2pot cell falls back to
// level 1 only when none of its pot cells found a level-0 pixel, and a 4pot cell falls back to
// level 2 only when none of its 2pot cells found anything.
PassPicks selectPass(const Maps& m, int pot) {
  const CandidateLevel& g0 = m.pyr[0];
  PassPicks picks;
  for (int y4 = 0; y4 < g0.height; y4 += 4 * pot) {
    for (int x4 = 0; x4 < g0.width; x4 += 4 * pot) {
      bool found4 = false;
      for (int y2 = y4; y2 < y4 + 4 * pot; y2 += 2 * pot) {
        for (int x2 = x4; x2 < x4 + 4 * pot; x2 += 2 * pot) {
          bool found2 = false;
          for (int y1 = y2; y1 < y2 + 2 * pot; y1 += pot) {
            for (int x1 = x2; x1 < x2 + 2 * pot; x1 += pot) {
              const int best = bestInCell(g0, m.interior, x1, y1, pot);
              if (best >= 0) {
                picks.pixels.push_back(best);
                found2 = true;
              }
            }
          }
          if (!found2) {
            const int best = bestCoarse(m, 1, {x2, y2, x2 + 2 * pot, y2 + 2 * pot});
            if (best >= 0) {
              picks.coarse.emplace_back(1, best);
              found2 = true;
            }
          }
          found4 |= found2;
        }
      }
      if (!found4) {
        const int best = bestCoarse(m, 2, {x4, y4, x4 + 4 * pot, y4 + 4 * pot});
        if (best >= 0) picks.coarse.emplace_back(2, best);
      }
    }
  }
  return picks;
}

// selectPass(m, 1).size() without picking: the dense first pass usually serves only to choose
// the cell size of the pass that is kept (36-45k picks on Kinect frames for a target of 4000),
// and its count is the pixels of each level a pass would take, found by rows instead of by
// nested cells (callgrind over 20 teddy200 frames: the pass took a quarter of a frame's
// instructions). Level 0: the interior's candidates; level 1: a 2x2 cell's coarse pixel when
// none of its level-0 pixels is a candidate; level 2: a 4x4 cell's when none of its 2x2 cells
// took anything. A coarse pixel counts where bestCoarse would read it (coarseInterior).
std::size_t countDensePass(const Maps& m) {
  const CandidateLevel& g0 = m.pyr[0];
  const CandidateLevel& g1 = m.pyr[1];
  const CandidateLevel& g2 = m.pyr[2];
  const Rect& in = m.interior;
  const Rect in1 = coarseInterior(m, 1), in2 = coarseInterior(m, 2);
  // The pass's 4x4 cells cover the image rounded up to multiples of 4: 2x2 cells per row and
  // column of that.
  const int cw = (g0.width + 3) / 4 * 2, ch = (g0.height + 3) / 4 * 2;
  std::vector<std::uint8_t> found(static_cast<std::size_t>(cw) * ch, 0);
  std::size_t count = 0;
  // A row's candidates as bytes (0 outside the interior, 2 cw of them), so that the count and
  // each cell's flag run over whole rows.
  std::vector<std::uint8_t> pick(2 * static_cast<std::size_t>(cw), 0);
  for (int y = in.y0; y < in.y1; ++y) {
    const float* row = &g0.value[static_cast<std::size_t>(y) * g0.width];
    int row_count = 0;
    for (int x = in.x0; x < in.x1; ++x) {
      pick[std::size_t(x)] = row[x] > 0.f;
      row_count += pick[std::size_t(x)];
    }
    count += std::size_t(row_count);
    std::uint8_t* cell = &found[static_cast<std::size_t>(y >> 1) * cw];
    for (int cx = 0; cx < cw; ++cx) {
      cell[cx] |= pick[2 * std::size_t(cx)] | pick[2 * std::size_t(cx) + 1];
    }
  }
  for (int cy = in1.y0; cy < in1.y1; ++cy) {
    const float* row = &g1.value[static_cast<std::size_t>(cy) * g1.width];
    std::uint8_t* cell = &found[static_cast<std::size_t>(cy) * cw];
    for (int cx = in1.x0; cx < in1.x1; ++cx) {
      const bool takes = cell[cx] == 0 && row[cx] > 0.f;
      count += takes;
      cell[cx] |= static_cast<std::uint8_t>(takes);
    }
  }
  for (int qy = in2.y0; qy < in2.y1; ++qy) {
    const std::uint8_t* top = &found[static_cast<std::size_t>(2 * qy) * cw];
    const std::uint8_t* bottom = top + cw;
    for (int qx = in2.x0; qx < in2.x1; ++qx) {
      const bool any = (top[2 * qx] | top[2 * qx + 1] | bottom[2 * qx] | bottom[2 * qx + 1]) != 0;
      count += !any && g2.at(qx, qy) > 0.f;
    }
  }
  return count;
}

// Fixed pseudo-random value of a pixel index (a 32-bit integer hash): thinning keeps the pixels
// with the smallest values, so the same image always keeps the same pixels.
std::uint32_t pixelHash(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

void thinTo(std::vector<int>& picks, std::size_t want) {
  if (picks.size() <= want) return;
  auto by_hash = [](int a, int b) {
    const std::uint32_t ha = pixelHash(static_cast<std::uint32_t>(a));
    const std::uint32_t hb = pixelHash(static_cast<std::uint32_t>(b));
    return ha != hb ? ha < hb : a < b;
  };
  std::nth_element(picks.begin(), picks.begin() + static_cast<std::ptrdiff_t>(want), picks.end(),
                   by_hash);
  picks.resize(want);
}

// First cell size: one at which a scene with ordinary texture (a strong pixel in about 45 % of
// the cells; 0.44-0.55 on the kitchen frames) gives over 4 times the target, so that the first
// pass usually falls below the reselection window. The reselection then predicts a larger cell
// from a dense pass; the fraction of cells that find a pixel grows slowly with the cell size, so
// that prediction, rounded down, errs towards too many points, which thinning removes exactly.
// 640x480 with 3000 points: pot 2.
int initialCellSize(int area, int want) {
  return std::max(1, static_cast<int>(std::sqrt(0.1 * area / want)) - 1);
}

// Gradient selection with the cell size adapted to the target: count ~ K / (pot + 1)^2.
std::vector<int> adaptiveSelect(const Maps& m, int want, int& pot) {
  pot = initialCellSize(m.gray.cols * m.gray.rows, want);
  // Cells of one pixel are only counted first: that pass is rarely the one kept.
  std::optional<PassPicks> pass;
  if (pot > 1) pass = selectPass(m, pot);
  const double have = static_cast<double>(pass ? pass->size() : countDensePass(m));
  const double ratio = have > 0 ? want / have : INFINITY;
  if ((ratio > 1.25 && pot > 1) || ratio < 0.25) {
    const double k = have * (pot + 1) * (pot + 1);
    int ideal = std::max(1, static_cast<int>(std::sqrt(k / want) - 1.0));  // rounded down
    ideal = ratio > 1.25 ? std::min(ideal, pot - 1) : std::max(ideal, pot + 1);
    pot = ideal;
    pass = selectPass(m, pot);
  } else if (!pass) {
    pass = selectPass(m, pot);
  }
  std::vector<int> picks = level0Pixels(m, std::move(*pass));
  thinTo(picks, static_cast<std::size_t>(want));
  return picks;
}

// In each 8x8 block, the first Canny edge pixel (row-major) inside the interior that is not
// selected yet. `taken` marks the selected pixels (one byte per pixel).
std::vector<int> cannyPixels(const cv::Mat& gray, const Rect& interior,
                             const std::vector<std::uint8_t>& taken) {
  cv::Mat blurred, edges;
  cv::blur(gray, blurred, cv::Size(3, 3));
  cv::Canny(blurred, edges, 0, 25, 3);
  std::vector<int> added;
  for (int by = 0; by < gray.rows; by += kCannyBlock) {
    for (int bx = 0; bx < gray.cols; bx += kCannyBlock) {
      const Rect r = Rect{bx, by, bx + kCannyBlock, by + kCannyBlock}.clip(interior);
      bool done = false;
      for (int v = r.y0; v < r.y1 && !done; ++v) {
        const auto* e = edges.ptr<std::uint8_t>(v);
        for (int u = r.x0; u < r.x1; ++u) {
          const int idx = v * gray.cols + u;
          if (e[u] != 0 && !taken[idx]) {
            added.push_back(idx);
            done = true;
            break;
          }
        }
      }
    }
  }
  return added;
}

// Pixels this far from every edge are never selected.
Rect interiorOf(const cv::Mat& gray) {
  return {kBorder, kBorder, gray.cols - kBorder, gray.rows - kBorder};
}

}  // namespace

namespace selection {
std::size_t passSize(const cv::Mat& gray, int pot) {
  const CandidatePyramid pyr = candidateMaps(gray);
  return selectPass({gray, pyr, interiorOf(gray)}, pot).size();
}

std::size_t densePassCount(const cv::Mat& gray) {
  const CandidatePyramid pyr = candidateMaps(gray);
  return countDensePass({gray, pyr, interiorOf(gray)});
}
}  // namespace selection

int targetPoints(const SelectionParams& params, cv::Size size) {
  if (!params.scale_with_image || params.target_points <= 0) return params.target_points;
  constexpr double kReferencePixels = 640.0 * 480.0;
  const double scale = std::sqrt(double(size.area()) / kReferencePixels);
  return std::max(1, int(std::lround(params.target_points * scale)));
}

Selection selectPixels(const cv::Mat& gray, const cv::Mat& depth, const SelectionParams& params) {
  if (gray.type() != CV_8UC1) throw std::invalid_argument("selectPixels: grey image must be 8UC1");
  if (depth.type() != CV_32FC1 || depth.size() != gray.size()) {
    throw std::invalid_argument("selectPixels: depth must be 32FC1 and the size of the image");
  }
  Selection out;
  const Rect interior = interiorOf(gray);
  const int target = targetPoints(params, gray.size());
  if (interior.empty() || target <= 0) return out;

  const CandidatePyramid pyr = selection::candidateMaps(gray);
  std::vector<int> picks = adaptiveSelect({gray, pyr, interior}, target, out.cell_size);
  out.gradient_pixels = static_cast<int>(picks.size());

  if (params.canny_fallback && 3 * out.gradient_pixels < target) {
    std::vector<std::uint8_t> taken(static_cast<std::size_t>(gray.cols) * gray.rows, 0);
    for (int idx : picks) taken[idx] = 1;
    const std::vector<int> edges = cannyPixels(gray, interior, taken);
    picks.insert(picks.end(), edges.begin(), edges.end());
    out.canny_used = true;
    out.canny_pixels = static_cast<int>(edges.size());
  }

  std::sort(picks.begin(), picks.end());  // pixel indices: row-major order
  out.pixels.reserve(picks.size());
  const SelectableDepth selectable(params);
  for (int idx : picks) {
    const int u = idx % gray.cols, v = idx / gray.cols;
    if (selectable(depth.at<float>(v, u))) out.pixels.emplace_back(u, v);
  }
  return out;
}

}  // namespace acvo
