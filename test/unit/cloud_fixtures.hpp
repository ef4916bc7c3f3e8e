// Random labelled clouds and an independent double-precision brute-force kernel, the oracle
// for the kernel and solver tests.
#pragma once

#include <cmath>
#include <random>

#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/params.hpp"

namespace acvo::test {

// Points on a few random patches (surface-like, as real semi-dense clouds are) with smooth labels.
inline LabelledCloud randomCloud(int n, unsigned seed, float extent = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  LabelledCloud c;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3f p(extent * u(rng), extent * u(rng), 2.0f + 0.5f * extent * u(rng));
    c.points.push_back(p);
    Label f;
    f << 0.5f + 0.4f * std::sin(3 * p.x()), 0.5f + 0.3f * std::cos(2 * p.y()),
        0.5f + 0.2f * std::sin(p.x() + p.y()), 0.3f * u(rng), 0.3f * u(rng);
    c.labels.push_back(f);
  }
  return c;
}

inline LabelledCloud transformed(const LabelledCloud& c, const Eigen::Isometry3d& T) {
  LabelledCloud out = c;
  for (auto& p : out.points) p = (T.cast<float>() * p);
  return out;
}

// sum_ij a_ij and friends in double, with the same sparsification rule (a >= threshold), for
// either engine's kernel constants (sigma, color_ell, color_sigma, sparsification).
struct BruteForce {
  double F = 0, F_d2 = 0;
  long nnz = 0;
  Eigen::Vector3d omega_sum = Eigen::Vector3d::Zero(), v_sum = Eigen::Vector3d::Zero();
};

template <typename KernelParams>
BruteForce bruteForce(const LabelledCloud& X, const LabelledCloud& Z, const Eigen::Isometry3d& T,
                      double ell, const KernelParams& p) {
  BruteForce b;
  for (std::size_t j = 0; j < Z.size(); ++j) {
    const Eigen::Vector3d y = T * Z.points[j].cast<double>();
    for (std::size_t i = 0; i < X.size(); ++i) {
      const Eigen::Vector3d x = X.points[i].cast<double>();
      const double d2 = (x - y).squaredNorm();
      const double c2 = (X.labels[i] - Z.labels[j]).cast<double>().squaredNorm();
      const double a = p.sigma * p.sigma * std::exp(-d2 / (2 * ell * ell)) * p.color_sigma *
                       p.color_sigma * std::exp(-c2 / (2 * p.color_ell * p.color_ell));
      if (a < p.sparsification) continue;
      b.F += a;
      b.F_d2 += a * d2;
      ++b.nnz;
      b.omega_sum += a * x.cross(y);
      b.v_sum += a * (y - x);
    }
  }
  return b;
}

}  // namespace acvo::test
