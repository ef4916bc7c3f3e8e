// The paper engine's kernel sums (docs/method.md §2-§4).
#include "acvo/registration/paper_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "acvo/math/se3.hpp"

namespace acvo {
namespace {

// The sums over one moving point's kept pairs: sum a x cross y, sum a (y - x), sum a, sum a d2.
struct PointSums {
  Eigen::Vector3f cross = Eigen::Vector3f::Zero(), diff = Eigen::Vector3f::Zero();
  float a = 0.0f, ad2 = 0.0f;
};

// The m > 0 candidates of the moving point placed at y (from the k-th of its chunk's lists):
// their squared distances and kernel values, computed for all of them at once; then those that
// count (inside the radius, kernel value at least the sparsification threshold) appended to
// `pairs` as (i, a) and summed. One point's few terms are summed in float.
template <typename Pairs>
inline PointSums keptPairs(CandidateLists::Chunk& cand, int k, int m, const Eigen::Vector3f& y,
                           const std::vector<Eigen::Vector3f>& X, float sigma2, float inv,
                           float r2, float sp, Pairs& pairs) {
  PointSums s;
  using Map = Eigen::Map<const Eigen::ArrayXf>;
  auto d2 = cand.scratch_d2.head(m);
  auto a = cand.scratch_a.head(m);
  d2 = (Map(cand.x.data() + k, m) - y.x()).square() +
       (Map(cand.y.data() + k, m) - y.y()).square() +
       (Map(cand.z.data() + k, m) - y.z()).square();
  a = sigma2 * (d2 * -inv).exp() * Map(cand.color.data() + k, m);
  for (int q = 0; q < m; ++q) {
    if (!(d2[q] < r2) || a[q] < sp) continue;
    const int i = cand.i[std::size_t(k) + std::size_t(q)];
    const float aq = a[q];
    pairs.push_back({i, aq});
    const Eigen::Vector3f& x = X[std::size_t(i)];
    s.cross += aq * x.cross(y);
    s.diff += aq * (y - x);
    s.a += aq;
    s.ad2 += aq * d2[q];
  }
  return s;
}

}  // namespace

double largestEll(const PaperParams& p) {
  double ell = std::max(p.ell_init, p.ell_max);
  if (p.ell_policy == EllPolicy::kFixedSchedule) ell = std::max(ell, 0.15);
  return ell;
}

SelfSums selfKernelSums(const PaperCloud& cloud, double ell, const PaperParams& p,
                        int first_row) {
  SelfSums s;
  const double sigma2 = p.sigma * p.sigma;
  const double sp = p.sparsification;
  const double inv = 1.0 / (2.0 * ell * ell);
  const int n = int(cloud.size());
  // Diagonal: distance 0, colour factor sigma_c^2.
  const double diag = sigma2 * p.color_sigma * p.color_sigma;
  if (diag >= sp) {
    const int rows = std::max(0, n - std::max(first_row, 0));
    s.sum += rows * diag;
    s.nnz += rows;
    s.nnz_all += n;
  }
  if (first_row <= 0) {
    // Every pair counts twice, (i, j) and (j, i): vectorised over the pair arrays.
    const Eigen::ArrayXf a =
        float(sigma2) * (cloud.self_d2 * float(-inv)).exp() * cloud.self_color;
    const auto kept = (a >= float(sp));
    s.sum += 2.0 * kept.select(a, 0.0f).cast<double>().sum();
    s.sum_d2 += 2.0 * kept.select(a * cloud.self_d2, 0.0f).cast<double>().sum();
    s.nnz += 2 * std::int64_t(kept.count());
    s.nnz_all += 2 * std::int64_t(kept.count());
    return s;
  }
  for (const auto& q : cloud.self_pairs) {
    const double a = sigma2 * std::exp(-q.d2 * inv) * q.color;
    if (a < sp) continue;
    s.nnz_all += 2;
    // The pair stands for the two ordered entries (i, j) and (j, i).
    const int entries = int(q.i >= first_row) + int(q.j >= first_row);
    s.sum += entries * a;
    s.sum_d2 += entries * a * q.d2;
    s.nnz += entries;
  }
  return s;
}

PaperKernel::PaperKernel(const LabelledCloud& fixed, const LabelledCloud& moving,
                         const VoxelGrid& grid, const PaperParams& params)
    : fixed_(fixed),
      moving_(moving),
      params_(params),
      k_(kernelConstants(params.sigma, params.color_ell, params.color_sigma,
                         params.sparsification)),
      lists_(fixed, moving, grid, k_),
      y_(moving.size()),
      chunks_(std::size_t(lists_.chunks())) {}

const CrossSums& PaperKernel::evaluate(const Eigen::Isometry3d& T, double ell) {
  ell_ = ell;
  const double r2_exact = spatialRadius2(ell, params_.sigma, params_.sparsification);
  const float r = float(std::sqrt(std::min(r2_exact, 1e6)));
  lists_.update(T, r);

  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const float r2 = r * r;
  const float inv = float(1.0 / (2.0 * ell * ell));
  const float sigma2 = k_.sigma2, sp = k_.sparsification;
  const auto& X = fixed_.points;
  const auto& Z = moving_.points;
  const int n = int(Z.size());

  forEachChunk(lists_.chunks(), [&](int c) {
    CandidateLists::Chunk& cand = lists_.chunk(c);
    ChunkPairs& out = chunks_[std::size_t(c)];
    out.pairs.clear();
    out.end.clear();
    // Per-chunk accumulation in double; one point's few terms are summed in float (keptPairs).
    CrossSums s;
    int k = 0;
    const int end = std::min(n, (c + 1) * kChunk);
    for (int j = c * kChunk; j < end; ++j) {
      const Eigen::Vector3f y = R * Z[std::size_t(j)] + t;
      y_[std::size_t(j)] = y;
      const int k_end = cand.end[std::size_t(j - c * kChunk)];
      const int m = k_end - k;
      PointSums p;
      if (m > 0) p = keptPairs(cand, k, m, y, X, sigma2, inv, r2, sp, out.pairs);
      k = k_end;
      if (p.a > 0.0f) ++s.matched;
      out.end.push_back(int(out.pairs.size()));
      s.omega += p.cross.cast<double>();
      s.v += p.diff.cast<double>();
      s.F += p.a;
      s.F_d2 += p.ad2;
    }
    s.nnz = std::int64_t(out.pairs.size());
    out.sums = s;
  });

  sums_ = CrossSums();
  for (const auto& chunk : chunks_) {
    sums_.omega += chunk.sums.omega;
    sums_.v += chunk.sums.v;
    sums_.F += chunk.sums.F;
    sums_.F_d2 += chunk.sums.F_d2;
    sums_.nnz += chunk.sums.nnz;
    sums_.matched += chunk.sums.matched;
  }
  sums_.omega /= params_.omega_scale;
  sums_.v /= params_.v_scale;
  return sums_;
}

StepSums PaperKernel::stepSums(const Eigen::Vector3d& omega_d, const Eigen::Vector3d& v_d) const {
  const Eigen::Vector3f omega = omega_d.cast<float>(), v = v_d.cast<float>();
  const double inv_unit = 1.0 / (ell_ * ell_);
  const auto& X = fixed_.points;
  const int n = int(y_.size());
  std::vector<StepSums> partial(chunks_.size());

  forEachChunk(int(chunks_.size()), [&](int c) {
    const ChunkPairs& chunk = chunks_[std::size_t(c)];
    double B = 0, C = 0, D = 0, E = 0;
    int k = 0;
    const int end = std::min(n, (c + 1) * kChunk);
    for (int j = c * kChunk; j < end; ++j) {
      const int k_end = chunk.end[std::size_t(j - c * kChunk)];
      if (k == k_end) continue;
      // The powers of the twist applied to y depend only on y: once per moving point.
      const Eigen::Vector3f y = y_[std::size_t(j)];
      const double inv_l2 = inv_unit;
      const Eigen::Vector3f x1 = omega.cross(y) + v;  // xi z
      const Eigen::Vector3f x2 = omega.cross(x1);     // xi^2 z = W^2 y + W v
      const Eigen::Vector3f x3 = omega.cross(x2);
      const Eigen::Vector3f x4 = omega.cross(x3);
      // Exponent of a_ij(t) = a_ij exp(beta t + gamma t^2 + delta t^3 + eps t^4 + O(t^5)), from
      // x - y(t) = d + t x1 - t^2/2 x2 + t^3/6 x3 - t^4/24 x4 with d = x - y. (the paper writes
      // these terms without exp's factorials; with them, C, D and E are the Taylor coefficients
      // of F, which the tests check against finite differences.)
      const double g_const = x1.squaredNorm();
      const double d_const = 0.5 * x1.dot(x2);
      const double e_const = 0.25 * x2.squaredNorm() + x1.dot(x3) / 3.0;
      for (; k < k_end; ++k) {
        const auto& pr = chunk.pairs[std::size_t(k)];
        const Eigen::Vector3f d = X[std::size_t(pr.i)] - y;
        const double beta = -inv_l2 * x1.dot(d);
        const double gamma = -0.5 * inv_l2 * (g_const - x2.dot(d));
        const double delta = inv_l2 * (d_const - x3.dot(d) / 6.0);
        const double eps = -0.5 * inv_l2 * (e_const - x4.dot(d) / 12.0);
        const double a = pr.a, b2 = beta * beta;
        B += a * beta;
        C += a * (gamma + 0.5 * b2);
        D += a * (delta + beta * gamma + b2 * beta / 6.0);
        E += a * (eps + beta * delta + 0.5 * b2 * gamma + 0.5 * gamma * gamma + b2 * b2 / 24.0);
      }
    }
    partial[std::size_t(c)] = {B, C, D, E};
  });

  StepSums s;
  for (const auto& p : partial) {
    s.B += p.B;
    s.C += p.C;
    s.D += p.D;
    s.E += p.E;
  }
  return s;
}

Matrix6d PaperKernel::curvature() const {
  // a(y) = k exp(-|x - y|^2 / 2l^2): d2a/dy2 = a (d d^T / l^4 - I / l^2), d = x - y, and
  // dy/dxi = [-[y]x, I] for y -> exp(xi^) y.
  const double inv_unit = 1.0 / (ell_ * ell_);
  const auto& X = fixed_.points;
  Matrix6d H = Matrix6d::Zero();
  const int n = int(y_.size());
  for (std::size_t c = 0; c < chunks_.size(); ++c) {
    const ChunkPairs& chunk = chunks_[std::size_t(c)];
    int k = 0;
    const int end = std::min(n, int(c + 1) * kChunk);
    for (int j = int(c) * kChunk; j < end; ++j) {
      const int k_end = chunk.end[std::size_t(j - int(c) * kChunk)];
      if (k == k_end) continue;
      const Eigen::Vector3d y = y_[std::size_t(j)].cast<double>();
      const double inv_l2 = inv_unit;
      Eigen::Matrix<double, 3, 6> J;
      J << -hat(y), Eigen::Matrix3d::Identity();
      Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
      for (; k < k_end; ++k) {
        const auto& pr = chunk.pairs[std::size_t(k)];
        const Eigen::Vector3d d = X[std::size_t(pr.i)].cast<double>() - y;
        M += pr.a * (d * d.transpose() * inv_l2 * inv_l2 - inv_l2 * Eigen::Matrix3d::Identity());
      }
      H += J.transpose() * M * J;
    }
  }
  return H;
}

}  // namespace acvo
