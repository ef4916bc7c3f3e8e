// The kernel a_ij, its sparsification, and the per-cloud structures the solver reuses:
// a uniform voxel grid for the cross-pair search and the self-kernel pairs (docs/method.md §2, §4).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "acvo/labelled_cloud.hpp"
#include "acvo/params.hpp"

namespace acvo {

// Smallest s* such that |g(s) - L_n(s)| <= tol for all s >= s*, where g(s) = exp(-1/(2 s^2))
// and L_n its expansion about s = infinity truncated at order n in 1/s (docs/method.md §5).
// Returns g(s*), the sparsification threshold divided by sigma^2.
// (4, 1e-3) -> 0.8315, (6, 1e-3) -> 0.6694.
double sparsificationThreshold(int order, double tolerance);

// Squared spatial radius beyond which sigma^2 exp(-d^2 / 2 ell^2) < threshold, i.e. no pair can
// survive sparsification whatever its colour. Zero when even d = 0 does not survive.
double spatialRadius2(double ell, double sigma, double threshold);

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

// A pair of distinct points of one cloud with their squared distance and colour factor.
struct SelfPair {
  int i = 0, j = 0;  // i < j
  float d2 = 0.0f;
  float color = 0.0f;
};

// A cloud ready for registration: its points, labels, search grid and self-kernel pairs,
// computed once per frame (the self-kernel of frame k is the fixed self-kernel of frame k+1).
// A cloud registered *to* (a reference: the fixed cloud of align) also needs the search grids
// of the other length-scales the solver uses (prepareReference).
struct PreparedCloud {
  LabelledCloud cloud;
  // cell = the search radius at the largest length-scale (adaptive, fixed_schedule) or at
  // ell_min (coarse_to_fine: the finest level's grid)
  VoxelGrid grid;
  bool reference = false;  // the grids below are built
  VoxelGrid coarse_grid;   // cell = the search radius at the coarse stage's length-scale
  // coarse_to_fine: one grid per level of levelElls but the last (which searches `grid`)
  std::vector<VoxelGrid> level_grids;
  std::vector<SelfPair> self_pairs;  // all pairs within that radius that can pass the threshold
  // The same pairs' d2 and colour factors as arrays, for vectorised sums per iteration.
  Eigen::ArrayXf self_d2, self_color;
  double ms_prepare = 0.0;

  std::size_t size() const { return cloud.size(); }
};

// Whether the kernel is shaped per point (coarse_to_fine with ell_depth_reference or
// depth_noise set).
inline bool perPointKernel(const SolverParams& p) {
  return p.ell_policy == EllPolicy::kCoarseToFine &&
         (p.ell_depth_reference > 0.0 || p.depth_noise > 0.0);
}
// Range-dependent length-scale (SolverParams::ell_depth_reference): a point at depth z uses
// ell * ellScale(z), z / reference clamped to [kMinEllScale, kMaxEllScale]; 1 when off.
constexpr float kMinEllScale = 0.5f, kMaxEllScale = 3.0f;
inline float ellScale(float z, const SolverParams& p) {
  if (!(p.ell_policy == EllPolicy::kCoarseToFine && p.ell_depth_reference > 0.0)) return 1.0f;
  const float s = z / float(p.ell_depth_reference);
  return s < kMinEllScale ? kMinEllScale : (s > kMaxEllScale ? kMaxEllScale : s);
}
// The largest factor by which a point's search radius may exceed the unit radius.
inline float maxEllScale(const SolverParams& p) {
  return perPointKernel(p) ? kMaxEllScale : 1.0f;
}

// The largest spatial length-scale the solver's main stage may use with these parameters.
double largestEll(const SolverParams& params);
// The length-scales of the coarse_to_fine levels: ell_init, ell_init * ell_reduction, ... down
// to ell_min (always the last).
std::vector<double> levelElls(const SolverParams& params);
// Cell of a search grid serving radii up to that of length-scale `ell`.
float gridCell(double ell, const SolverParams& params);

// The self-kernel pairs and the grid that found them, and with `as_reference` the search grids
// a fixed cloud needs as well (prepareReference).
PreparedCloud prepareCloud(LabelledCloud cloud, const SolverParams& params,
                           bool as_reference = true);
// Builds what a cloud registered *to* needs beyond prepareCloud(..., false), once (a keyframe
// when it becomes one); returns the milliseconds it took (0 when already done).
double prepareReference(PreparedCloud& cloud, const SolverParams& params);

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
