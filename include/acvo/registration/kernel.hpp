// What both engines share of the kernel a_ij (docs/method.md §2, §5): its sparsification and
// the radius it implies, the colour factor, a uniform voxel grid over a fixed cloud, and the
// candidate lists that each engine's kernel pass runs over (the fixed points near each moving
// point, rebuilt only when a point may have left their margin).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "acvo/labelled_cloud.hpp"

namespace acvo {

// Smallest s* such that |g(s) - L_n(s)| <= tol for all s >= s*, where g(s) = exp(-1/(2 s^2))
// and L_n its expansion about s = infinity truncated at order n in 1/s (docs/method.md §5).
// Returns g(s*), the sparsification threshold divided by sigma^2.
// (4, 1e-3) -> 0.8315, (6, 1e-3) -> 0.6694.
double sparsificationThreshold(int order, double tolerance);

// Squared spatial radius beyond which sigma^2 exp(-d^2 / 2 ell^2) < threshold, i.e. no pair can
// survive sparsification whatever its colour. Zero when even d = 0 does not survive.
double spatialRadius2(double ell, double sigma, double threshold);

// Cell of a search grid serving radii up to that of length-scale `ell` (times max_scale, the
// largest factor by which a point's own radius may exceed it).
float gridCell(double ell, double sigma, double sparsification, float max_scale = 1.0f);

// Colour factor sigma_c^2 exp(-|f - g|^2 / 2 ell_c^2).
inline float colorFactor(const Label& f, const Label& g, float color_ell2x2_inv,
                         float color_sigma2) {
  return color_sigma2 * std::exp(-(f - g).squaredNorm() * color_ell2x2_inv);
}

// A uniform grid over a cloud's bounding box; cells of `cell` metres. Points are stored in cell
// order so that a row of cells along x is one contiguous range.
class VoxelGrid {
 public:
  VoxelGrid() = default;
  VoxelGrid(const std::vector<Eigen::Vector3f>& points, float cell);

  float cell() const { return cell_; }
  bool empty() const { return order_.empty(); }
  // Calls f(index) for every point in the 3x3x3 cells around q (a superset of the points
  // within `cell` of q).
  template <typename F>
  void forEachCandidate(const Eigen::Vector3f& q, F&& f) const;

 private:
  float cell_ = 0.0f;
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  int nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<int> cell_start_;  // size nx*ny*nz + 1
  std::vector<int> order_;       // point indices sorted by cell
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
  };

  // `grid` indexes the fixed cloud's points; its cell must be at least the largest search
  // radius used.
  CandidateLists(const LabelledCloud& fixed, const LabelledCloud& moving, const VoxelGrid& grid,
                 const KernelConstants& k);

  // Per moving point, its search radius as a multiple of the unit radius, with their smallest
  // and the largest they may reach (default: all 1). Invalidates the lists.
  void setSearchScales(std::vector<float> scales, float min_scale, float max_scale);
  float searchScale(int j) const { return search_scale_[std::size_t(j)]; }

  // Makes the lists valid for the moving points placed by T and searched within r times their
  // scale. Lists are built with a margin so that several iterations reuse them; they are rebuilt
  // when a point may have left the margin, or when the radius has shrunk so much that they carry
  // mostly useless candidates. The margin never exceeds the grid cell (the grid only guarantees
  // neighbours within one cell).
  void update(const Eigen::Isometry3d& T, float r);

  int chunks() const { return int(chunks_.size()); }
  Chunk& chunk(int c) { return chunks_[std::size_t(c)]; }
  int builds() const { return builds_; }

 private:
  void build(const Eigen::Isometry3d& T, float radius);

  const LabelledCloud& fixed_;
  const LabelledCloud& moving_;
  const VoxelGrid& grid_;
  KernelConstants k_;
  std::vector<float> search_scale_;
  float min_scale_ = 1.0f, max_scale_ = 1.0f;
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
void VoxelGrid::forEachCandidate(const Eigen::Vector3f& q, F&& f) const {
  if (order_.empty()) return;
  const Eigen::Vector3f r = ((q - origin_) / cell_).array().floor();
  // Range check before the conversion to int: a query far outside the grid, or not finite,
  // would not fit an int (undefined behaviour); NaN fails every comparison.
  if (!(r.x() >= -1.0f && r.y() >= -1.0f && r.z() >= -1.0f && r.x() <= float(nx_) &&
        r.y() <= float(ny_) && r.z() <= float(nz_))) {
    return;
  }
  const int cx = static_cast<int>(r.x()), cy = static_cast<int>(r.y()),
            cz = static_cast<int>(r.z());
  const int x0 = std::max(cx - 1, 0), x1 = std::min(cx + 1, nx_ - 1);
  if (x0 > x1) return;
  for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, nz_ - 1); ++z) {
    for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, ny_ - 1); ++y) {
      const int row = (z * ny_ + y) * nx_;
      const int begin = cell_start_[row + x0], end = cell_start_[row + x1 + 1];
      for (int k = begin; k < end; ++k) f(order_[k]);
    }
  }
}

}  // namespace acvo
