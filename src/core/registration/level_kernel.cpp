// The default engine's kernel pass (docs/method.md §6): per moving point, its candidate pairs'
// kernel values under the point's own length-scale (in proportion to its depth, stretched along
// its viewing ray by the depth noise), and the Gauss-Newton normal equations of the quadratic
// that minorises F there.
#include <algorithm>
#include <cmath>

#include "acvo/registration/coarse_to_fine.hpp"

namespace acvo {

float ellScale(float z, const CoarseToFineParams& p) {
  if (!(p.ell_depth_reference > 0.0)) return 1.0f;
  const float s = z / float(p.ell_depth_reference);
  return s < kMinEllScale ? kMinEllScale : (s > kMaxEllScale ? kMaxEllScale : s);
}

namespace {

struct PairSums {
  Eigen::Vector3f x = Eigen::Vector3f::Zero();  // sum of a x over the kept pairs
  float a = 0.0f;                              // sum of a
  int kept = 0;
};

// The pairs of one moving point that count (inside the radius, kernel value at least the
// sparsification threshold), summed without a branch: about 40% of a point's candidates count,
// in no order a branch predictor learns. A short list (the finest level's hold four on average)
// in one pass; a longer one has the others' values zeroed in place and is summed in vector
// packets, where one chain of additions waited on the one before.
constexpr int kShortList = 8;
PairSums keptPairSums(int m, const float* d2, float* a, const float* x, const float* y,
                      const float* z, float r2, float sp) {
  PairSums p;
  if (m < kShortList) {
    for (int q = 0; q < m; ++q) {
      const bool keep = (d2[q] < r2) & (a[q] >= sp);
      const float w = keep ? a[q] : 0.0f;
      p.a += w;
      p.x += w * Eigen::Vector3f(x[q], y[q], z[q]);
      p.kept += int(keep);
    }
    return p;
  }
  for (int q = 0; q < m; ++q) {
    const bool keep = (d2[q] < r2) & (a[q] >= sp);
    a[q] = keep ? a[q] : 0.0f;
    p.kept += int(keep);
  }
  using Map = Eigen::Map<const Eigen::ArrayXf>;
  const Map w(a, m);
  p.a = w.sum();
  p.x = Eigen::Vector3f((w * Map(x, m)).sum(), (w * Map(y, m)).sum(), (w * Map(z, m)).sum());
  return p;
}

// The m > 0 candidates of one moving point placed at y (from the k-th of its chunk's lists), with
// its ray, depth-noise share kappa, 1 / (2 ell_j^2) `inv` and squared radius r2: their squared
// distances and kernel values, computed for all of them at once, then the sums of those that
// count.
inline PairSums candidateSums(CandidateLists::Chunk& chunk, int k, int m, const Eigen::Vector3f& y,
                              const Eigen::Vector3f& ray, float kappa, float sigma2, float inv,
                              float r2, float sp) {
  using Map = Eigen::Map<const Eigen::ArrayXf>;
  auto d2 = chunk.scratch_d2.head(m);
  auto a = chunk.scratch_a.head(m);
  const Map cx(chunk.x.data() + k, m), cy(chunk.y.data() + k, m), cz(chunk.z.data() + k, m);
  d2 = (cx - y.x()).square() + (cy - y.y()).square() + (cz - y.z()).square();
  if (kappa > 0.0f) {
    const auto along = (cx - y.x()) * ray.x() + (cy - y.y()) * ray.y() + (cz - y.z()) * ray.z();
    a = sigma2 * ((d2 - kappa * along.square()) * -inv).exp() * Map(chunk.color.data() + k, m);
  } else {
    a = sigma2 * (d2 * -inv).exp() * Map(chunk.color.data() + k, m);
  }
  return keptPairSums(m, d2.data(), a.data(), cx.data(), cy.data(), cz.data(), r2, sp);
}

// A chunk's H from moments of its matched points: sum w a, sum w a y, sum w a y y^T and
// sum w a kappa ray ray^T.
struct Moments {
  double m0 = 0.0;
  Eigen::Vector3d m1 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d m2 = Eigen::Matrix3d::Zero(), along = Eigen::Matrix3d::Zero();
};

// A matched point's share (its pairs' sums x_sum, a_sum > 0; s2 its squared length-scale
// factor): its pairs weigh (x_i - y)^T W (x_i - y) by a_ij / ell_j^2, W = I - kappa ray ray^T;
// they share y, so they enter through sum a and sum a x. With J = [-hat(y), I] and ray along y
// (so J^T ray = [0; ray]): J^T W J = [[|y|^2 I - y y^T, hat(y)], [hat(y)^T, I - kappa ray
// ray^T]], summed as moments; J^T W e = [y x W e; W e].
inline void addMatched(LevelSums& s, Moments& mo, const Eigen::Vector3f& y,
                       const Eigen::Vector3f& ray, const Eigen::Vector3f& x_sum, float a_sum,
                       float s2, float kappa) {
  ++s.matched;
  const double wa = double(a_sum) / double(s2);
  const Eigen::Vector3d yd = y.cast<double>(), rd = ray.cast<double>();
  mo.m0 += wa;
  mo.m1 += wa * yd;
  mo.m2.noalias() += (wa * yd) * yd.transpose();
  mo.along.noalias() += (wa * double(kappa) * rd) * rd.transpose();
  const Eigen::Vector3d e = (x_sum.cast<double>() - double(a_sum) * yd) / double(s2);
  const Eigen::Vector3d we = e - double(kappa) * rd * rd.dot(e);
  s.g.head<3>() += yd.cross(we);
  s.g.tail<3>() += we;
}

// J^T W J summed over a chunk's matched points, from their moments.
void setH(LevelSums& s, const Moments& mo) {
  s.H.topLeftCorner<3, 3>() = mo.m2.trace() * Eigen::Matrix3d::Identity() - mo.m2;
  s.H.topRightCorner<3, 3>() = hat(mo.m1);
  s.H.bottomLeftCorner<3, 3>() = hat(mo.m1).transpose();
  s.H.bottomRightCorner<3, 3>() = mo.m0 * Eigen::Matrix3d::Identity() - mo.along;
}

}  // namespace

bool perPointKernel(const CoarseToFineParams& p) {
  return p.ell_depth_reference > 0.0 || p.depth_noise > 0.0;
}

LevelKernel::LevelKernel(const LabelledCloud& fixed, const LabelledCloud& moving,
                         const VoxelGrid& grid, const CoarseToFineParams& params)
    : moving_(moving),
      params_(params),
      k_(kernelConstants(params.sigma, params.color_ell, params.color_sigma,
                         params.sparsification)),
      lists_(fixed, moving, grid, k_),
      scale_(moving.size(), 1.0f),
      kappa_(moving.size(), 0.0f),
      partial_(std::size_t(lists_.chunks())) {}

void LevelKernel::shapeFor(double ell) {
  shaped_ell_ = ell;
  std::vector<float> search(moving_.size(), 1.0f);
  for (std::size_t j = 0; j < moving_.size(); ++j) {
    const float z = moving_.points[j].z();
    scale_[j] = ellScale(z, params_);
    // Both points' depth noise along the ray against the kernel's own width there: the part of
    // the distance along the ray counts (1 - kappa) times.
    const float noise = float(params_.depth_noise) * z * z;
    const float l = float(ell) * scale_[j];
    kappa_[j] = 2.0f * noise * noise / (l * l + 2.0f * noise * noise);
    search[j] = std::min(scale_[j] / std::sqrt(1.0f - kappa_[j]), kMaxEllScale);
  }
  // New shapes, new lists.
  lists_.setSearchScales(std::move(search));
}

const LevelSums& LevelKernel::evaluate(const Eigen::Isometry3d& T, double ell) {
  if (perPointKernel(params_) && ell != shaped_ell_) shapeFor(ell);
  const double r2_exact = spatialRadius2(ell, params_.sigma, params_.sparsification);
  const float r = float(std::sqrt(std::min(r2_exact, 1e6)));
  lists_.update(T, r);

  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const float r2_unit = r * r;
  const float inv_unit = float(1.0 / (2.0 * ell * ell));
  const float sigma2 = k_.sigma2, sp = k_.sparsification;
  const auto& Z = moving_.points;
  const int n = int(Z.size());

  forEachChunk(lists_.chunks(), [&](int c) {
    CandidateLists::Chunk& chunk = lists_.chunk(c);
    // Per-chunk accumulation in double; one point's few terms are summed in float.
    LevelSums s;
    Moments mo;
    int k = 0;
    const int end = std::min(n, (c + 1) * kChunk);
    for (int j = c * kChunk; j < end; ++j) {
      const Eigen::Vector3f y = R * Z[std::size_t(j)] + t;
      const float scale = scale_[std::size_t(j)], search = lists_.searchScale(j);
      const float s2 = scale * scale;
      const float r2 = r2_unit * search * search, inv = inv_unit / s2;
      const float kappa = kappa_[std::size_t(j)];
      const Eigen::Vector3f ray = y.normalized();
      const int k_end = chunk.end[std::size_t(j - c * kChunk)];
      const int m = k_end - k;
      PairSums p;
      if (m > 0) {
        p = candidateSums(chunk, k, m, y, ray, kappa, sigma2, inv, r2, sp);
        s.nnz += p.kept;
      }
      k = k_end;
      if (p.a > 0.0f) addMatched(s, mo, y, ray, p.x, p.a, s2, kappa);
      s.F += p.a;
    }
    setH(s, mo);
    partial_[std::size_t(c)] = s;
  });

  sums_ = LevelSums();
  for (const auto& s : partial_) {
    sums_.F += s.F;
    sums_.nnz += s.nnz;
    sums_.H += s.H;
    sums_.g += s.g;
    sums_.matched += s.matched;
  }
  return sums_;
}

}  // namespace acvo
