// What both engines share of the kernel a_ij (docs/method.md §2, §5): its sparsification and
// the radius it implies, the colour factor, a search grid of columns over a fixed cloud, and the
// candidate lists that each engine's kernel pass runs over (the fixed points near each moving
// point, rebuilt only when a point may have left their margin).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "acvo/cloud/labelled_cloud.hpp"

namespace acvo {

// Smallest s* such that |g(s) - L_n(s)| <= tol for all s >= s*, where g(s) = exp(-1/(2 s^2))
// and L_n its expansion about s = infinity truncated at order n in 1/s (docs/method.md §5).
// Returns g(s*), the sparsification threshold divided by sigma^2.
// (4, 1e-3) -> 0.8315, (6, 1e-3) -> 0.6694.
double sparsificationThreshold(int order, double tolerance);

// Squared spatial radius beyond which sigma^2 exp(-d^2 / 2 ell^2) < threshold, i.e. no pair can
// survive sparsification whatever its colour. Zero when even d = 0 does not survive.
double spatialRadius2(double ell, double sigma, double threshold);

// The radius candidate lists are built with for a kernel radius r: a margin beyond it lets
// several iterations reuse them.
inline float listRadius(float r) { return 1.3f * r + 0.002f; }

// Cell of a search grid for the radius of length-scale `ell` (queries of other radii cover more
// or fewer cells).
float gridCell(double ell, double sigma, double sparsification);

// Colour factor sigma_c^2 exp(-|f - g|^2 / 2 ell_c^2), from the labels or from |f - g|^2.
inline float colorFactorOf(float label_d2, float color_ell2x2_inv, float color_sigma2) {
  return color_sigma2 * std::exp(-label_d2 * color_ell2x2_inv);
}
inline float colorFactor(const Label& f, const Label& g, float color_ell2x2_inv,
                         float color_sigma2) {
  return colorFactorOf((f - g).squaredNorm(), color_ell2x2_inv, color_sigma2);
}

// A search grid over a cloud: square columns of `cell` metres in x and y, each column's points
// sorted by z. A camera's cloud spans metres in depth but holds about one surface per viewing
// ray, so columns keep the index small (a dense 3-D grid at the finest search radius would need
// millions of cells) and a query reads only the few points of the columns it covers whose z
// is in range.
class VoxelGrid {
 public:
  VoxelGrid() = default;
  VoxelGrid(const std::vector<Eigen::Vector3f>& points, float cell);

  float cell() const { return cell_; }
  bool empty() const { return order_.empty(); }
  int columns() const { return nx_ * ny_; }
  // The most columns a grid over `points` finite points has: beyond it the cells are coarsened.
  // Camera clouds use up to 10 columns per point (teddy200 to 10 m; 1-2 in rooms); a few hundred
  // points from absurd intrinsics made grids of 4 million mostly empty columns, each built and
  // zeroed again at every level.
  static double maxColumns(std::size_t points) {
    return std::min(4e6, 4096.0 + 32.0 * double(points));
  }
  // Calls f(index, point) for every point in the box of half-width `radius` around q, so for
  // every point within `radius` of q (and a few more from the columns' corners).
  template <typename F>
  void forEachWithin(const Eigen::Vector3f& q, float radius, F&& f) const;
  // The same box as runs of the grid's order: f(begin, end) for each column the box covers that
  // has points in its z range, in the order forEachWithin visits them; index(k) and xs()[k],
  // ys()[k], zs()[k] give the k-th point of that order.
  template <typename F>
  void forEachRun(const Eigen::Vector3f& q, float radius, F&& f) const;
  int index(int k) const { return order_[std::size_t(k)]; }
  // The points' coordinates in the same order, one array each (for loops over a run that the
  // compiler vectorises).
  const float* xs() const { return x_.data(); }
  const float* ys() const { return y_.data(); }
  const float* zs() const { return z_.data(); }
  int size() const { return int(order_.size()); }
  // forEachWithin(q, cell()).
  template <typename F>
  void forEachCandidate(const Eigen::Vector3f& q, F&& f) const {
    forEachWithin(q, cell_, std::forward<F>(f));
  }

 private:
  float cell_ = 0.0f;
  Eigen::Vector2f origin_ = Eigen::Vector2f::Zero();
  int nx_ = 0, ny_ = 0;
  std::vector<int> column_start_;  // size nx*ny + 1
  std::vector<int> order_;         // point indices by column, by z within a column
  std::vector<float> x_, y_, z_;   // their coordinates, in the same order (read contiguously)
};

// The kernel's constants as the per-pair loops use them.
struct KernelConstants {
  float sigma2 = 0.01f;        // sigma^2
  float color_sigma2 = 1.0f;   // sigma_c^2
  float color_inv = 50.0f;     // 1 / (2 ell_c^2)
  float sparsification = 0.0f;
};
KernelConstants kernelConstants(double sigma, double color_ell, double color_sigma,
                                double sparsification);

constexpr int kLabelDim = int(Label::RowsAtCompileTime);

// Moving points per chunk. Chunks are the unit of parallel work and of the reductions, which
// run over them in a fixed order: results do not depend on the number of threads.
constexpr int kChunk = 64;

template <typename F>
void forEachChunk(int chunks, F&& f) {
  tbb::parallel_for(tbb::blocked_range<int>(0, chunks, 1),
                    [&](const tbb::blocked_range<int>& r) {
                      for (int c = r.begin(); c != r.end(); ++c) f(c);
                    },
                    tbb::simple_partitioner());
}

// The candidate fixed points of each moving point: every fixed point within the list radius of
// where the moving point was when the lists were built, whose colour factor lets it pass the
// threshold at distance 0. Colour does not depend on the transform: its factor is kept here.
// Coordinates are copied, contiguous per moving point, so that a kernel pass runs over them
// with vector instructions instead of gathering fixed points by index.
class CandidateLists {
 public:
  struct Chunk {
    std::vector<int> end;  // per moving point of the chunk: end index into the arrays below
    std::vector<int> i;
    std::vector<float> color;  // sigma_c^2 exp(-|f_i - g_j|^2 / 2 l_c^2)
    std::vector<float> x, y, z;
    Eigen::ArrayXf scratch_d2, scratch_a;  // work buffers as long as the chunk's longest list
    // build's work buffers: a run's squared distances and label distances, and the grid
    // positions of one point's candidates (within reach, colour not ruled out) with their label
    // distances.
    std::vector<float> run_d2, run_label_d2;
    std::vector<int> near;
    std::vector<float> near_label_d2;
  };

  // `grid` indexes the fixed cloud's points (any cell: queries cover their own radius).
  CandidateLists(const LabelledCloud& fixed, const LabelledCloud& moving, const VoxelGrid& grid,
                 const KernelConstants& k);

  // Per moving point, its search radius as a multiple of the unit radius (default: all 1; each
  // positive). Invalidates the lists.
  void setSearchScales(std::vector<float> scales);
  float searchScale(int j) const { return search_scale_[std::size_t(j)]; }

  // Makes the lists valid for the moving points placed by T and searched within r times their
  // scale. Lists are built with a margin so that several iterations reuse them; they are rebuilt
  // when a point may have left the margin, or when the radius has shrunk so much that they carry
  // mostly useless candidates.
  void update(const Eigen::Isometry3d& T, float r);

  int chunks() const { return int(chunks_.size()); }
  Chunk& chunk(int c) { return chunks_[std::size_t(c)]; }
  int builds() const { return builds_; }

 private:
  void build(const Eigen::Isometry3d& T, float radius);

  const LabelledCloud& moving_;
  const VoxelGrid& grid_;
  // The fixed labels in the grid's order, one array per channel (read contiguously by runs).
  std::array<std::vector<float>, kLabelDim> grid_labels_;
  KernelConstants k_;
  std::vector<float> search_scale_;
  std::vector<Chunk> chunks_;
  // The lists stay valid while every moving point stays within radius_ - r of where it was at
  // T_ (r: the current search radius).
  bool valid_ = false;
  Eigen::Isometry3d T_ = Eigen::Isometry3d::Identity();
  float radius_ = 0.0f;
  int builds_ = 0;
};

// Every k-th point of a cloud (k = size / count, at least 1), labels with them.
LabelledCloud stridedSubset(const LabelledCloud& cloud, int count);

// ---------------------------------------------------------------------------------------------
template <typename F>
void VoxelGrid::forEachWithin(const Eigen::Vector3f& q, float radius, F&& f) const {
  forEachRun(q, radius, [&](int begin, int end) {
    for (int k = begin; k < end; ++k) {
      const auto i = std::size_t(k);
      f(order_[i], Eigen::Vector3f(x_[i], y_[i], z_[i]));
    }
  });
}

template <typename F>
void VoxelGrid::forEachRun(const Eigen::Vector3f& q, float radius, F&& f) const {
  if (order_.empty()) return;
  // Column range in float first: a query far outside the grid, or not finite, would not fit an
  // int (undefined behaviour); NaN fails every comparison.
  const float x_lo = std::floor((q.x() - radius - origin_.x()) / cell_);
  const float x_hi = std::floor((q.x() + radius - origin_.x()) / cell_);
  const float y_lo = std::floor((q.y() - radius - origin_.y()) / cell_);
  const float y_hi = std::floor((q.y() + radius - origin_.y()) / cell_);
  if (!(x_hi >= 0.0f && y_hi >= 0.0f && x_lo < float(nx_) && y_lo < float(ny_))) return;
  const float z_lo = q.z() - radius, z_hi = q.z() + radius;
  if (!(z_lo <= z_hi)) return;
  const int x0 = int(std::max(x_lo, 0.0f)), x1 = int(std::min(x_hi, float(nx_ - 1)));
  const int y0 = int(std::max(y_lo, 0.0f)), y1 = int(std::min(y_hi, float(ny_ - 1)));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const int column = y * nx_ + x;
      const auto begin = z_.begin() + column_start_[std::size_t(column)];
      const auto end = z_.begin() + column_start_[std::size_t(column) + 1];
      // A third of the columns a query covers are empty, a sixth hold no point in its z range.
      if (begin == end || end[-1] < z_lo || *begin > z_hi) continue;
      // Both ends by binary search: a column a query reaches holds 35-40 points, 25 of them in
      // its z range (teddy200), which a scan for the far end read one by one.
      const auto first = std::lower_bound(begin, end, z_lo);
      const auto last = std::upper_bound(first, end, z_hi);
      if (last != first) f(int(first - z_.begin()), int(last - z_.begin()));
    }
  }
}

}  // namespace acvo
