#include "acvo/kernel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace acvo {

double sparsificationThreshold(int order, double tolerance) {
  // With u = 1/(2 s^2), g = exp(-u) and the expansion truncated at order n in 1/s keeps the
  // terms (-u)^k / k! for k <= n/2. The truncation error grows with u from 0, so the answer is
  // exp(-u*) for the first u* where it reaches the tolerance.
  const int kmax = order / 2;
  auto error = [kmax](double u) {
    double term = 1.0, sum = 1.0;
    for (int k = 1; k <= kmax; ++k) {
      term *= -u / k;
      sum += term;
    }
    return std::abs(std::exp(-u) - sum);
  };
  double lo = 0.0, hi = 0.0;
  const double du = 1e-3;
  while (error(hi) <= tolerance) {
    lo = hi;
    hi += du;
    if (hi > 50.0) return std::exp(-hi);  // tolerance never reached: threshold vanishes
  }
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (error(mid) <= tolerance ? lo : hi) = mid;
  }
  return std::exp(-lo);
}

double spatialRadius2(double ell, double sigma, double threshold) {
  const double s2 = sigma * sigma;
  if (threshold <= 0.0) return std::numeric_limits<double>::infinity();
  if (threshold >= s2) return 0.0;
  return -2.0 * ell * ell * std::log(threshold / s2);
}

double largestEll(const SolverParams& p) {
  double ell = std::max(p.ell_init, p.ell_max);
  if (p.ell_policy == EllPolicy::kFixedSchedule) ell = std::max(ell, 0.15);
  if (p.ell_policy == EllPolicy::kCoarseToFine) ell = p.ell_init;
  return ell;
}

std::vector<double> levelElls(const SolverParams& p) {
  std::vector<double> ells;
  for (double ell = p.ell_init; ell > p.ell_min * (1.0 + 1e-9); ell *= p.ell_reduction) {
    ells.push_back(ell);
  }
  ells.push_back(p.ell_min);
  return ells;
}

VoxelGrid::VoxelGrid(const std::vector<Eigen::Vector3f>& points, float cell) : cell_(cell) {
  if (points.empty() || !(cell > 0.0f)) return;
  // A non-finite point (from absurd intrinsics) has no place in the grid and no neighbours: it is
  // left out, and the box spans the finite points only.
  auto finite = [](const Eigen::Vector3f& p) { return p.allFinite(); };
  const auto first = std::find_if(points.begin(), points.end(), finite);
  if (first == points.end()) return;
  Eigen::Vector3f lo = *first, hi = *first;
  for (const auto& p : points) {
    if (!finite(p)) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // A cloud spread far beyond the radius would make a huge dense grid: coarsen the cells then
  // (candidates stay a superset of the true neighbours, searches only get slower). The extent is
  // taken in double: hi - lo of finite floats may overflow float.
  constexpr double kMaxCells = 4e6;
  const Eigen::Vector3d extent = hi.cast<double>() - lo.cast<double>();
  for (;;) {
    const Eigen::Vector3d n = (extent / double(cell_)).array().floor() + 1.0;
    if (n.x() * n.y() * n.z() <= kMaxCells) {
      nx_ = int(n.x()), ny_ = int(n.y()), nz_ = int(n.z());
      break;
    }
    cell_ *= 1.5f;
  }
  origin_ = lo;
  const int cells = nx_ * ny_ * nz_;
  const Eigen::Vector3f top(float(nx_ - 1), float(ny_ - 1), float(nz_ - 1));
  std::vector<int> cell_of(points.size(), -1);
  cell_start_.assign(cells + 1, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!finite(points[i])) continue;
    // Clamped before the conversion to int: p - origin may overflow float to +inf.
    const Eigen::Vector3f r = ((points[i] - origin_) / cell_).cwiseMin(top);
    const int x = int(r.x()), y = int(r.y()), z = int(r.z());
    cell_of[i] = (z * ny_ + y) * nx_ + x;
    ++cell_start_[cell_of[i] + 1];
  }
  for (int c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  order_.resize(cell_start_.back());
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (cell_of[i] >= 0) order_[fill[cell_of[i]]++] = int(i);
  }
}

float gridCell(double ell, const SolverParams& p) {
  const double r2 = spatialRadius2(ell, p.sigma, p.sparsification);
  // Cells a little larger than the search radius: the solver's candidate lists carry a margin
  // beyond the radius and a grid only guarantees neighbours within one cell.
  return (std::isfinite(r2) && r2 > 0.0 ? 1.3f * float(std::sqrt(r2)) + 0.002f : 0.1f) *
         maxEllScale(p);
}

double prepareReference(PreparedCloud& cloud, const SolverParams& p) {
  if (cloud.reference) return 0.0;
  const auto t0 = std::chrono::steady_clock::now();
  if (p.ell_policy == EllPolicy::kCoarseToFine) {
    // The finest level searches `grid` (built for the self pairs at ell_min).
    const std::vector<double> ells = levelElls(p);
    for (std::size_t level = 0; level + 1 < ells.size(); ++level) {
      cloud.level_grids.emplace_back(cloud.cloud.points, gridCell(ells[level], p));
    }
  } else if (p.coarse_ell > 0.0) {
    cloud.coarse_grid = VoxelGrid(cloud.cloud.points, gridCell(p.coarse_ell, p));
  }
  cloud.reference = true;
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  cloud.ms_prepare += ms;
  return ms;
}

PreparedCloud prepareCloud(LabelledCloud cloud, const SolverParams& p, bool as_reference) {
  const auto t0 = std::chrono::steady_clock::now();
  PreparedCloud out;
  out.cloud = std::move(cloud);
  const bool levels = p.ell_policy == EllPolicy::kCoarseToFine;
  // Self pairs serve the length-scale update and the inner product at the final length-scale;
  // coarse_to_fine needs them at its finest level only.
  const double self_ell = levels ? p.ell_min : largestEll(p);
  const double r2 = spatialRadius2(self_ell, p.sigma, p.sparsification);
  out.grid = VoxelGrid(out.cloud.points, gridCell(self_ell, p));

  const float sigma2 = float(p.sigma * p.sigma);
  const float color_sigma2 = float(p.color_sigma * p.color_sigma);
  const float color_inv = float(1.0 / (2.0 * p.color_ell * p.color_ell));
  const float sp = float(p.sparsification);
  const auto& pts = out.cloud.points;
  const auto& labels = out.cloud.labels;
  for (int i = 0; i < int(pts.size()); ++i) {
    out.grid.forEachCandidate(pts[i], [&](int j) {
      if (j <= i) return;
      const float d2 = (pts[i] - pts[j]).squaredNorm();
      if (!(d2 < r2)) return;
      const float c = colorFactor(labels[i], labels[j], color_inv, color_sigma2);
      // Necessary condition whatever the length-scale: the pair at distance 0 must pass.
      if (sigma2 * c < sp) return;
      out.self_pairs.push_back({i, j, d2, c});
    });
  }
  out.self_d2.resize(Eigen::Index(out.self_pairs.size()));
  out.self_color.resize(Eigen::Index(out.self_pairs.size()));
  for (std::size_t k = 0; k < out.self_pairs.size(); ++k) {
    out.self_d2[Eigen::Index(k)] = out.self_pairs[k].d2;
    out.self_color[Eigen::Index(k)] = out.self_pairs[k].color;
  }
  out.ms_prepare =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (as_reference) prepareReference(out, p);
  return out;
}

}  // namespace acvo
