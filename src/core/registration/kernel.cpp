// The kernel pieces both engines share: sparsification, the voxel grid, the candidate lists.
#include "acvo/registration/kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

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

namespace {

// The box of the finite points' x and y, and how many they are (none: count 0). A non-finite
// point (from absurd intrinsics) has no place in the grid and no neighbours.
struct FiniteBox {
  Eigen::Vector2f lo = Eigen::Vector2f::Zero(), hi = Eigen::Vector2f::Zero();
  std::size_t count = 0;
};
FiniteBox finiteBox(const std::vector<Eigen::Vector3f>& points) {
  auto finite = [](const Eigen::Vector3f& p) { return p.allFinite(); };
  FiniteBox box;
  const auto first = std::find_if(points.begin(), points.end(), finite);
  if (first == points.end()) return box;
  box.lo = first->head<2>(), box.hi = first->head<2>();
  for (const auto& p : points) {
    if (!finite(p)) continue;
    box.lo = box.lo.cwiseMin(p.head<2>());
    box.hi = box.hi.cwiseMax(p.head<2>());
    ++box.count;
  }
  return box;
}

// Each column's run of `order` (the point indices, by column) sorted by depth.
void sortColumnsByDepth(const std::vector<Eigen::Vector3f>& points,
                        const std::vector<int>& column_start, std::vector<int>& order) {
  for (std::size_t c = 0; c + 1 < column_start.size(); ++c) {
    const auto begin = order.begin() + column_start[c];
    const auto end = order.begin() + column_start[c + 1];
    if (end - begin > 1) {
      std::sort(begin, end, [&](int a, int b) {
        return points[std::size_t(a)].z() < points[std::size_t(b)].z();
      });
    }
  }
}

}  // namespace

VoxelGrid::VoxelGrid(const std::vector<Eigen::Vector3f>& points, float cell) : cell_(cell) {
  if (points.empty() || !(cell > 0.0f)) return;
  // Non-finite points are left out, and the box spans the finite points only.
  const FiniteBox box = finiteBox(points);
  if (box.count == 0) return;
  const Eigen::Vector2f lo = box.lo, hi = box.hi;
  // A cloud spread far beyond the radius would make a huge grid of empty columns: coarsen the
  // cells then (candidates stay a superset of the true neighbours, searches only get slower).
  // The extent is taken in double: hi - lo of finite floats may overflow float.
  const double max_columns = maxColumns(box.count);
  const Eigen::Vector2d extent = hi.cast<double>() - lo.cast<double>();
  for (;;) {
    const Eigen::Vector2d n = (extent / double(cell_)).array().floor() + 1.0;
    if (n.x() * n.y() <= max_columns) {
      nx_ = int(n.x()), ny_ = int(n.y());
      break;
    }
    cell_ *= 1.5f;
  }
  origin_ = lo;
  const int columns = nx_ * ny_;
  const Eigen::Vector2f top(float(nx_ - 1), float(ny_ - 1));
  std::vector<int> column_of(points.size(), -1);
  column_start_.assign(std::size_t(columns) + 1, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    // Clamped before the conversion to int: p - origin may overflow float to +inf.
    const Eigen::Vector2f r = ((points[i].head<2>() - origin_) / cell_).cwiseMin(top);
    column_of[i] = int(r.y()) * nx_ + int(r.x());
    ++column_start_[std::size_t(column_of[i]) + 1];
  }
  for (int c = 0; c < columns; ++c) column_start_[std::size_t(c) + 1] += column_start_[std::size_t(c)];
  order_.resize(std::size_t(column_start_.back()));
  std::vector<int> fill(column_start_.begin(), column_start_.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (column_of[i] >= 0) order_[std::size_t(fill[std::size_t(column_of[i])]++)] = int(i);
  }
  sortColumnsByDepth(points, column_start_, order_);
  x_.resize(order_.size());
  y_.resize(order_.size());
  z_.resize(order_.size());
  for (std::size_t k = 0; k < order_.size(); ++k) {
    const Eigen::Vector3f& p = points[std::size_t(order_[k])];
    x_[k] = p.x();
    y_[k] = p.y();
    z_[k] = p.z();
  }
}

float gridCell(double ell, double sigma, double sparsification) {
  const double r2 = spatialRadius2(ell, sigma, sparsification);
  // Twice the radius the candidate lists are built with (CandidateLists::update): points at 1-3 m
  // search 1.3-3 times it, so a query covers 2-4 columns a side. Instructions of the list builds
  // over 20 kitchen7s_dev frames (callgrind): 407 M with cells of one radius, 365 M of 1.5,
  // 352 M of 2, 350 M of 3.
  return std::isfinite(r2) && r2 > 0.0 ? 2.0f * listRadius(float(std::sqrt(r2))) : 0.1f;
}

KernelConstants kernelConstants(double sigma, double color_ell, double color_sigma,
                                double sparsification) {
  KernelConstants k;
  k.sigma2 = float(sigma * sigma);
  k.color_sigma2 = float(color_sigma * color_sigma);
  k.color_inv = float(1.0 / (2.0 * color_ell * color_ell));
  k.sparsification = float(sparsification);
  return k;
}

CandidateLists::CandidateLists(const LabelledCloud& fixed, const LabelledCloud& moving,
                               const VoxelGrid& grid, const KernelConstants& k)
    : moving_(moving),
      grid_(grid),
      k_(k),
      search_scale_(moving.size(), 1.0f),
      chunks_((moving.size() + kChunk - 1) / kChunk) {
  for (int c = 0; c < kLabelDim; ++c) {
    std::vector<float>& channel = grid_labels_[std::size_t(c)];
    channel.resize(std::size_t(grid.size()));
    for (int k = 0; k < grid.size(); ++k) {
      channel[std::size_t(k)] = fixed.labels[std::size_t(grid.index(k))][c];
    }
  }
}

void CandidateLists::setSearchScales(std::vector<float> scales) {
  search_scale_ = std::move(scales);
  valid_ = false;
  radius_ = 0.0f;
}

void CandidateLists::update(const Eigen::Isometry3d& T, float r) {
  // How far the moving points have moved since the lists were built, each in units of its own
  // search radius (exactly: a bound through ||dR|| |z|max is loose enough to force a rebuild
  // after a tenth of a degree).
  float moved = INFINITY;
  if (valid_) {
    const Eigen::Matrix3f dR = (T.linear() - T_.linear()).cast<float>();
    const Eigen::Vector3f dt = (T.translation() - T_.translation()).cast<float>();
    float worst2 = 0.0f;
    for (std::size_t j = 0; j < moving_.size(); ++j) {
      const float s = search_scale_[j];
      worst2 = std::max(worst2, (dR * moving_.points[j] + dt).squaredNorm() / (s * s));
    }
    moved = std::sqrt(worst2);
  }
  if (r + moved > radius_ || radius_ > 1.6f * r + 0.005f) build(T, listRadius(r));
}

namespace {

// Squared distances from q and label distances from g of a run of the grid's points (their
// coordinates and label channels from `begin` on), in the order Eigen's squaredNorm sums 3 and
// 5 floats. A function of its own, with the arrays not aliased, so that the compiler vectorises
// it (inlined in the build's loop, it did not).
void runDistances(std::size_t len, const float* __restrict px, const float* __restrict py,
                  const float* __restrict pz, const Eigen::Vector3f& q,
                  const std::array<const float*, kLabelDim>& labels, int begin, const Label& g,
                  float* __restrict d2, float* __restrict label_d2) {
  static_assert(kLabelDim == 5, "the label distance below sums five channels");
  const float qx = q.x(), qy = q.y(), qz = q.z();
  const float g0 = g[0], g1 = g[1], g2 = g[2], g3 = g[3], g4 = g[4];
  const float* __restrict l0 = labels[0] + begin;
  const float* __restrict l1 = labels[1] + begin;
  const float* __restrict l2 = labels[2] + begin;
  const float* __restrict l3 = labels[3] + begin;
  const float* __restrict l4 = labels[4] + begin;
  for (std::size_t k = 0; k < len; ++k) {
    const float dx = px[k] - qx, dy = py[k] - qy, dz = pz[k] - qz;
    d2[k] = dx * dx + (dy * dy + dz * dz);
    const float e0 = l0[k] - g0, e1 = l1[k] - g1, e2 = l2[k] - g2, e3 = l3[k] - g3,
                e4 = l4[k] - g4;
    label_d2[k] = ((e0 * e0 + e2 * e2) + (e1 * e1 + e3 * e3)) + e4 * e4;
  }
}

// sigma^2 colorFactor >= sparsification as a bound on the label distance: most pairs in reach
// fail on colour, and the bound spares them the exponential (-1: no pair can pass).
float labelDistanceBound(const KernelConstants& k) {
  const float ratio = k.sigma2 * k.color_sigma2 / k.sparsification;
  return !(ratio >= 1.0f) ? -1.0f : (k.color_inv > 0.0f ? std::log(ratio) / k.color_inv : INFINITY);
}

// Room in the chunk's work buffers for a run of len grid points after `within` near ones.
inline void reserveRun(CandidateLists::Chunk& chunk, std::size_t within, std::size_t len) {
  if (chunk.run_d2.size() < len) {
    chunk.run_d2.resize(2 * len);
    chunk.run_label_d2.resize(2 * len);
  }
  if (chunk.near.size() < within + len) {
    chunk.near.resize(2 * (within + len));
    chunk.near_label_d2.resize(2 * (within + len));
  }
}

// The chunk's `within` near grid points (chunk.near) appended to its lists after the `kept`
// pairs so far, each with its label distance in place of its colour factor (finishChunk's).
inline void appendNear(CandidateLists::Chunk& chunk, std::size_t within, const VoxelGrid& grid,
                       std::size_t& kept) {
  const std::size_t most = kept + within;
  if (chunk.i.size() < most) {
    chunk.i.resize(most);
    chunk.color.resize(most);
    chunk.x.resize(most);
    chunk.y.resize(most);
    chunk.z.resize(most);
  }
  const float* gx = grid.xs();
  const float* gy = grid.ys();
  const float* gzs = grid.zs();
  for (std::size_t w = 0; w < within; ++w) {
    const int k = chunk.near[w];
    chunk.i[kept] = grid.index(k);
    chunk.color[kept] = chunk.near_label_d2[w];  // its colour factor below, for the chunk
    chunk.x[kept] = gx[k];
    chunk.y[kept] = gy[k];
    chunk.z[kept] = gzs[k];
    ++kept;
  }
}

// The chunk's lists cut to its `kept` pairs, their colour factors from their label distances,
// and its scratch buffers as long as its `longest` list.
void finishChunk(CandidateLists::Chunk& chunk, std::size_t kept, int longest,
                 const KernelConstants& k) {
  chunk.i.resize(kept);
  chunk.color.resize(kept);
  chunk.x.resize(kept);
  chunk.y.resize(kept);
  chunk.z.resize(kept);
  // The colour factors of the chunk's pairs from their label distances, vectorised (one
  // std::exp per pair took 2-3% of a frame).
  Eigen::Map<Eigen::ArrayXf> color(chunk.color.data(), Eigen::Index(chunk.color.size()));
  color = k.color_sigma2 * (color * -k.color_inv).exp();
  if (chunk.scratch_d2.size() < longest) {
    chunk.scratch_d2.resize(longest);
    chunk.scratch_a.resize(longest);
  }
}

}  // namespace

void CandidateLists::build(const Eigen::Isometry3d& T, float radius) {
  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const auto& Z = moving_.points;
  const auto& gz = moving_.labels;
  const int n = int(Z.size());
  const float label_d2_max = labelDistanceBound(k_);
  // Both tests run over a column's run of grid points at once, vectorised: three in four points
  // of a run fail the first and about half the rest the second. A pair is then kept by adding
  // the tests' outcome to the count instead of branching on it, in no order a branch predictor
  // learns (the mispredictions were most of a build's time).
  const float* gx = grid_.xs();
  const float* gy = grid_.ys();
  const float* gzs = grid_.zs();
  std::array<const float*, kLabelDim> gl{};
  for (int c = 0; c < kLabelDim; ++c) gl[std::size_t(c)] = grid_labels_[std::size_t(c)].data();
  forEachChunk(int(chunks_.size()), [&](int c) {
    Chunk& chunk = chunks_[std::size_t(c)];
    chunk.end.clear();
    std::size_t kept = 0;
    int longest = 0, start = 0;
    const int end = std::min(n, (c + 1) * kChunk);
    for (int j = c * kChunk; j < end; ++j) {
      const Eigen::Vector3f y = R * Z[std::size_t(j)] + t;
      const float rj = radius * search_scale_[std::size_t(j)];
      const float radius2 = rj * rj;
      const Label& g = gz[std::size_t(j)];
      std::size_t within = 0;  // of chunk.near and chunk.near_label_d2
      grid_.forEachRun(y, rj, [&](int begin, int stop) {
        const std::size_t len = std::size_t(stop - begin);
        reserveRun(chunk, within, len);
        float* d2 = chunk.run_d2.data();
        float* label_d2 = chunk.run_label_d2.data();
        runDistances(len, gx + begin, gy + begin, gzs + begin, y, gl, begin, g, d2, label_d2);
        int* near = chunk.near.data();
        float* near_label_d2 = chunk.near_label_d2.data();
        for (std::size_t q = 0; q < len; ++q) {
          near[within] = begin + int(q);
          near_label_d2[within] = label_d2[q];
          within += std::size_t((d2[q] < radius2) & (label_d2[q] <= label_d2_max));
        }
      });
      appendNear(chunk, within, grid_, kept);
      chunk.end.push_back(int(kept));
      longest = std::max(longest, chunk.end.back() - start);
      start = chunk.end.back();
    }
    finishChunk(chunk, kept, longest, k_);
  });
  T_ = T;
  radius_ = radius;
  valid_ = true;
  ++builds_;
}

LabelledCloud stridedSubset(const LabelledCloud& cloud, int count) {
  LabelledCloud subset;
  const int n = int(cloud.size());
  const int stride = std::max(1, n / std::max(count, 1));
  for (int j = 0; j < n; j += stride) {
    subset.points.push_back(cloud.points[std::size_t(j)]);
    subset.labels.push_back(cloud.labels[std::size_t(j)]);
  }
  return subset;
}

}  // namespace acvo
