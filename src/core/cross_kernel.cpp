#include "acvo/cross_kernel.hpp"

#include "acvo/se3.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace acvo {
namespace {

// Moving points per chunk. Chunks are the unit of parallel work and of the reduction, which
// runs over them in a fixed order: results do not depend on the number of threads.
constexpr int kChunk = 64;

template <typename F>
void forEachChunk(int chunks, F&& f) {
  tbb::parallel_for(tbb::blocked_range<int>(0, chunks, 1),
                    [&](const tbb::blocked_range<int>& r) {
                      for (int c = r.begin(); c != r.end(); ++c) f(c);
                    },
                    tbb::simple_partitioner());
}

}  // namespace

SelfSums selfKernelSums(const PreparedCloud& cloud, double ell, const SolverParams& p,
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
  }
  if (first_row <= 0) {
    // Every pair counts twice, (i, j) and (j, i): vectorised over the pair arrays.
    const Eigen::ArrayXf a =
        float(sigma2) * (cloud.self_d2 * float(-inv)).exp() * cloud.self_color;
    const auto kept = (a >= float(sp));
    s.sum += 2.0 * kept.select(a, 0.0f).cast<double>().sum();
    s.sum_d2 += 2.0 * kept.select(a * cloud.self_d2, 0.0f).cast<double>().sum();
    s.nnz += 2 * std::int64_t(kept.count());
    return s;
  }
  for (const auto& q : cloud.self_pairs) {
    const double a = sigma2 * std::exp(-q.d2 * inv) * q.color;
    if (a < sp) continue;
    // The pair stands for the two ordered entries (i, j) and (j, i).
    const int entries = int(q.i >= first_row) + int(q.j >= first_row);
    s.sum += entries * a;
    s.sum_d2 += entries * a * q.d2;
    s.nnz += entries;
  }
  return s;
}

CrossKernel::CrossKernel(const PreparedCloud& fixed, const PreparedCloud& moving,
                         const SolverParams& params, const VoxelGrid* grid)
    : fixed_(fixed), moving_(moving), grid_(grid ? *grid : fixed.grid), params_(params) {
  y_.resize(moving_.size());
  scale_.resize(moving_.size(), 1.0f);
  search_scale_.resize(moving_.size(), 1.0f);
  kappa_.resize(moving_.size(), 0.0f);
  chunks_.resize((moving_.size() + kChunk - 1) / kChunk);
}

void CrossKernel::buildCandidates(const Eigen::Isometry3d& T, float radius) {
  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const float sigma2 = float(params_.sigma * params_.sigma);
  const float color_sigma2 = float(params_.color_sigma * params_.color_sigma);
  const float color_inv = float(1.0 / (2.0 * params_.color_ell * params_.color_ell));
  const float sp = float(params_.sparsification);
  const auto& X = fixed_.cloud.points;
  const auto& fx = fixed_.cloud.labels;
  const auto& Z = moving_.cloud.points;
  const auto& gz = moving_.cloud.labels;
  const int n = int(Z.size());
  forEachChunk(int(chunks_.size()), [&](int c) {
    Chunk& chunk = chunks_[c];
    chunk.cand_end.clear();
    chunk.cand_i.clear();
    chunk.cand_color.clear();
    chunk.cand_x.clear();
    chunk.cand_y.clear();
    chunk.cand_z.clear();
    int longest = 0, start = 0;
    const int end = std::min(n, (c + 1) * kChunk);
    for (int j = c * kChunk; j < end; ++j) {
      const Eigen::Vector3f y = R * Z[j] + t;
      const float radius2 = (radius * search_scale_[j]) * (radius * search_scale_[j]);
      grid_.forEachCandidate(y, [&](int i) {
        if (!((X[i] - y).squaredNorm() < radius2)) return;
        const float cf = colorFactor(fx[i], gz[j], color_inv, color_sigma2);
        if (sigma2 * cf < sp) return;  // fails at any distance
        chunk.cand_i.push_back(i);
        chunk.cand_color.push_back(cf);
        chunk.cand_x.push_back(X[i].x());
        chunk.cand_y.push_back(X[i].y());
        chunk.cand_z.push_back(X[i].z());
      });
      chunk.cand_end.push_back(int(chunk.cand_i.size()));
      longest = std::max(longest, chunk.cand_end.back() - start);
      start = chunk.cand_end.back();
    }
    if (chunk.scratch_d2.size() < longest) {
      chunk.scratch_d2.resize(longest);
      chunk.scratch_a.resize(longest);
    }
  });
  list_T_ = T;
  list_radius_ = radius;
  lists_valid_ = true;
  ++list_builds_;
}

const CrossSums& CrossKernel::evaluate(const Eigen::Isometry3d& T, double ell) {
  if (perPointKernel(params_) && ell != scale_ell_) {
    // Per-point length-scales depend on ell (the depth-noise term): new scales, new lists.
    scale_ell_ = ell;
    min_scale_ = kMaxEllScale;
    for (std::size_t j = 0; j < moving_.size(); ++j) {
      const float z = moving_.cloud.points[j].z();
      scale_[j] = ellScale(z, params_);
      // Both points' depth noise along the ray against the kernel's own width there.
      const float noise = float(params_.depth_noise) * z * z;
      const float l = float(ell) * scale_[j];
      kappa_[j] = 2.0f * noise * noise / (l * l + 2.0f * noise * noise);
      search_scale_[j] = std::min(scale_[j] / std::sqrt(1.0f - kappa_[j]), kMaxEllScale);
      min_scale_ = std::min(min_scale_, search_scale_[j]);
    }
    lists_valid_ = false;
    list_radius_ = 0.0f;
  }
  ell_ = ell;
  const double r2_exact = spatialRadius2(ell, params_.sigma, params_.sparsification);
  const float r = float(std::sqrt(std::min(r2_exact, 1e6)));
  // How far the moving points have moved since the lists were built (exactly: a bound through
  // ||dR|| |z|max is loose enough to force a rebuild after a tenth of a degree).
  float moved = INFINITY;
  if (lists_valid_) {
    const Eigen::Matrix3f dR = (T.linear() - list_T_.linear()).cast<float>();
    const Eigen::Vector3f dt = (T.translation() - list_T_.translation()).cast<float>();
    float worst2 = 0.0f;
    for (const auto& z : moving_.cloud.points) worst2 = std::max(worst2, (dR * z + dt).squaredNorm());
    // In units of each point's own length-scale the smallest scale moved the most.
    moved = std::sqrt(worst2) / min_scale_;
  }
  // Lists are built with a margin so that several iterations reuse them; they are rebuilt when
  // a point may have left the margin, or when the radius has shrunk enough that the lists carry
  // mostly useless candidates. The margin never exceeds the grid cell (the grid only
  // guarantees neighbours within one cell).
  const float cell = grid_.cell() / maxEllScale(params_);
  if (r + moved > list_radius_ || list_radius_ > 1.6f * r + 0.005f) {
    buildCandidates(T, std::min(1.3f * r + 0.002f, std::max(cell, r)));
  }

  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const float r2_unit = r * r;
  const float inv_unit = float(1.0 / (2.0 * ell * ell));
  const float sigma2 = float(params_.sigma * params_.sigma);
  const float sp = float(params_.sparsification);
  const auto& X = fixed_.cloud.points;
  const auto& Z = moving_.cloud.points;
  const int n = int(Z.size());

  forEachChunk(int(chunks_.size()), [&](int c) {
    Chunk& chunk = chunks_[c];
    chunk.pairs.clear();
    chunk.pair_end.clear();
    // Per-chunk accumulation in double; one point's few terms are summed in float.
    Eigen::Vector3d omega = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
    Matrix6d gn_H = Matrix6d::Zero();
    Vector6d gn_g = Vector6d::Zero();
    double F = 0.0, F_d2 = 0.0;
    std::int64_t matched = 0;
    int k = 0;
    const int end = std::min(n, (c + 1) * kChunk);
    for (int j = c * kChunk; j < end; ++j) {
      const Eigen::Vector3f y = R * Z[j] + t;
      y_[j] = y;
      const float s2 = scale_[j] * scale_[j];
      const float r2 = r2_unit * search_scale_[j] * search_scale_[j], inv = inv_unit / s2;
      const float kappa = kappa_[j];
      const Eigen::Vector3f ray = y.normalized();
      Eigen::Vector3f cross_sum = Eigen::Vector3f::Zero(), diff_sum = Eigen::Vector3f::Zero();
      Eigen::Vector3f x_sum = Eigen::Vector3f::Zero();
      float a_sum = 0.0f, ad2_sum = 0.0f;
      const int k_end = chunk.cand_end[j - c * kChunk];
      const int m = k_end - k;
      if (m > 0) {
        // Vectorised: squared distances and kernel values of all candidates of this point.
        using Map = Eigen::Map<const Eigen::ArrayXf>;
        auto d2 = chunk.scratch_d2.head(m);
        auto a = chunk.scratch_a.head(m);
        d2 = (Map(chunk.cand_x.data() + k, m) - y.x()).square() +
             (Map(chunk.cand_y.data() + k, m) - y.y()).square() +
             (Map(chunk.cand_z.data() + k, m) - y.z()).square();
        if (kappa > 0.0f) {
          // Depth noise stretches the kernel along the viewing ray (SolverParams::depth_noise):
          // the part of the distance along the ray counts (1 - kappa) times.
          const auto along = (Map(chunk.cand_x.data() + k, m) - y.x()) * ray.x() +
                             (Map(chunk.cand_y.data() + k, m) - y.y()) * ray.y() +
                             (Map(chunk.cand_z.data() + k, m) - y.z()) * ray.z();
          a = sigma2 * ((d2 - kappa * along.square()) * -inv).exp() *
              Map(chunk.cand_color.data() + k, m);
        } else {
          a = sigma2 * (d2 * -inv).exp() * Map(chunk.cand_color.data() + k, m);
        }
        for (int q = 0; q < m; ++q) {
          if (!(d2[q] < r2) || a[q] < sp) continue;
          const int i = chunk.cand_i[k + q];
          const float aq = a[q];
          chunk.pairs.push_back({i, aq});
          const Eigen::Vector3f d = y - X[i];
          cross_sum += aq * X[i].cross(y);
          diff_sum += aq * d;
          x_sum += aq * X[i];
          a_sum += aq;
          ad2_sum += aq * d2[q];
        }
      }
      k = k_end;
      if (a_sum > 0.0f) ++matched;
      chunk.pair_end.push_back(int(chunk.pairs.size()));
      omega += cross_sum.cast<double>();
      v += diff_sum.cast<double>();
      if (a_sum > 0.0f) {
        // Gauss-Newton normal equations of the minorising quadratic (see CrossSums): this
        // point's pairs weigh (x_i - y)^T W (x_i - y) by a_ij / ell_j^2, W = I - kappa ray ray^T;
        // they share y, so they enter through sum a and sum a x.
        const double w = 1.0 / double(s2);
        const Eigen::Vector3d yd = y.cast<double>(), rd = ray.cast<double>();
        const Eigen::Matrix3d W = Eigen::Matrix3d::Identity() - double(kappa) * rd * rd.transpose();
        Eigen::Matrix<double, 3, 6> J;
        J << -hat(yd), Eigen::Matrix3d::Identity();
        const Eigen::Matrix<double, 6, 3> JtW = J.transpose() * W;
        gn_H += (w * double(a_sum)) * JtW * J;
        gn_g += w * JtW * (x_sum.cast<double>() - double(a_sum) * yd);
      }
      F += a_sum;
      F_d2 += ad2_sum;
    }
    chunk.sums.omega = omega;
    chunk.sums.v = v;
    chunk.sums.F = F;
    chunk.sums.F_d2 = F_d2;
    chunk.sums.nnz = std::int64_t(chunk.pairs.size());
    chunk.sums.gn_H = gn_H;
    chunk.sums.gn_g = gn_g;
    chunk.sums.matched = matched;
  });

  sums_ = CrossSums();
  for (const auto& chunk : chunks_) {
    sums_.omega += chunk.sums.omega;
    sums_.v += chunk.sums.v;
    sums_.F += chunk.sums.F;
    sums_.F_d2 += chunk.sums.F_d2;
    sums_.nnz += chunk.sums.nnz;
    sums_.gn_H += chunk.sums.gn_H;
    sums_.gn_g += chunk.sums.gn_g;
    sums_.matched += chunk.sums.matched;
  }
  sums_.omega /= params_.omega_scale;
  sums_.v /= params_.v_scale;
  return sums_;
}

StepSums CrossKernel::stepSums(const Eigen::Vector3d& omega_d, const Eigen::Vector3d& v_d) const {
  const Eigen::Vector3f omega = omega_d.cast<float>(), v = v_d.cast<float>();
  const double inv_unit = 1.0 / (ell_ * ell_);
  const auto& X = fixed_.cloud.points;
  const int n = int(y_.size());
  std::vector<StepSums> partial(chunks_.size());

  forEachChunk(int(chunks_.size()), [&](int c) {
    const Chunk& chunk = chunks_[c];
    double B = 0, C = 0, D = 0, E = 0;
    int k = 0;
    const int end = std::min(n, (c + 1) * kChunk);
    for (int j = c * kChunk; j < end; ++j) {
      const int k_end = chunk.pair_end[j - c * kChunk];
      if (k == k_end) continue;
      // The powers of the twist applied to y depend only on y: once per moving point.
      const Eigen::Vector3f y = y_[j];
      const double inv_l2 = inv_unit / double(scale_[j] * scale_[j]);
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
        const auto& pr = chunk.pairs[k];
        const Eigen::Vector3f d = X[pr.i] - y;
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
    partial[c] = {B, C, D, E};
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

Eigen::Matrix<double, 6, 6> CrossKernel::curvature() const {
  // a(y) = k exp(-|x - y|^2 / 2l^2): d2a/dy2 = a (d d^T / l^4 - I / l^2), d = x - y, and
  // dy/dxi = [-[y]x, I] for y -> exp(xi^) y.
  const double inv_unit = 1.0 / (ell_ * ell_);
  const auto& X = fixed_.cloud.points;
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  const int n = int(y_.size());
  for (std::size_t c = 0; c < chunks_.size(); ++c) {
    const Chunk& chunk = chunks_[c];
    int k = 0;
    const int end = std::min(n, int(c + 1) * kChunk);
    for (int j = int(c) * kChunk; j < end; ++j) {
      const int k_end = chunk.pair_end[j - int(c) * kChunk];
      if (k == k_end) continue;
      const Eigen::Vector3d y = y_[j].cast<double>();
      const double inv_l2 = inv_unit / double(scale_[j] * scale_[j]);
      Eigen::Matrix<double, 3, 6> J;
      J << -hat(y), Eigen::Matrix3d::Identity();
      Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
      for (; k < k_end; ++k) {
        const auto& pr = chunk.pairs[k];
        const Eigen::Vector3d d = X[pr.i].cast<double>() - y;
        M += pr.a * (d * d.transpose() * inv_l2 * inv_l2 - inv_l2 * Eigen::Matrix3d::Identity());
      }
      H += J.transpose() * M * J;
    }
  }
  return H;
}

}  // namespace acvo
