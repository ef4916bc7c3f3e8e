// Kernel, sparsification and neighbour structures (docs/method.md §2, §5).
#include <gtest/gtest.h>

#include "acvo/registration/coarse_to_fine.hpp"
#include "acvo/registration/kernel.hpp"
#include "acvo/registration/paper.hpp"
#include "acvo/registration/paper_kernel.hpp"
#include "acvo/math/se3.hpp"
#include "cloud_fixtures.hpp"

namespace acvo {
namespace {

TEST(Sparsification, ThresholdsFromTheSensitivityAnalysis) {
  EXPECT_NEAR(sparsificationThreshold(4, 1e-3), 0.8315, 5e-5);
  EXPECT_NEAR(sparsificationThreshold(6, 1e-3), 0.6694, 5e-5);
  EXPECT_NEAR(sparsificationThreshold(4, 1e-2), 0.6673, 5e-5);
  EXPECT_NEAR(sparsificationThreshold(6, 1e-4), 0.7995, 5e-5);
  // The paper's table value for sigma = 0.1.
  EXPECT_NEAR(0.01 * sparsificationThreshold(4, 1e-3), 8.315e-3, 5e-7);
}

TEST(Sparsification, RadiusIsWhereTheSpatialFactorReachesTheThreshold) {
  const double r2 = spatialRadius2(0.1, 0.1, 8.315e-3);
  EXPECT_NEAR(0.01 * std::exp(-r2 / (2 * 0.01)), 8.315e-3, 1e-12);
  EXPECT_EQ(spatialRadius2(0.1, 0.1, 0.02), 0.0);  // even distance 0 fails
}

TEST(VoxelGrid, CandidatesContainEveryPointWithinTheRadius) {
  const LabelledCloud c = test::randomCloud(2000, 7, 0.5f);
  const float cell = 0.09f;
  VoxelGrid grid(c.points, cell);
  std::mt19937 rng(8);
  std::uniform_int_distribution<int> pick(0, 1999);
  // Radii below, at and well above the cell: a query covers its own radius whatever the cell.
  for (const float radius : {0.4f * cell, cell, 3.2f * cell}) {
    std::size_t within = 0, seen_count = 0;
    for (int q = 0; q < 200; ++q) {
      const Eigen::Vector3f query = c.points[pick(rng)] + Eigen::Vector3f(0.01f, -0.02f, 0.03f);
      std::vector<char> seen(c.size(), 0);
      grid.forEachWithin(query, radius, [&](int i, const Eigen::Vector3f& x) {
        ASSERT_EQ(x, c.points[std::size_t(i)]);
        ASSERT_FALSE(seen[i]) << "point " << i << " visited twice";
        seen[i] = 1;
        ++seen_count;
      });
      for (std::size_t i = 0; i < c.size(); ++i) {
        if ((c.points[i] - query).norm() < radius) {
          ++within;
          ASSERT_TRUE(seen[i]) << "point " << i << " missed at radius " << radius;
        }
      }
    }
    ASSERT_GT(within, 100u) << "the test needs neighbours";
    // Candidates come from the columns the radius covers (on average 2r + cell wide), cut to
    // the radius in z: as many as the ball's points times the box's volume over the ball's
    // (measured 9.8, 3.7, 2.0 against 9.7, 4.3, 2.6 expected; edges thin the larger boxes).
    const double box = std::pow(2.0 * radius + cell, 2) * 2.0 * radius;
    const double ball = 4.0 / 3.0 * M_PI * std::pow(radius, 3);
    EXPECT_LT(double(seen_count), 1.1 * box / ball * double(within)) << "radius " << radius;
  }
}

TEST(VoxelGrid, FewPointsSpreadFarMakeAFewColumns) {
  // 300 points over 2 km (as absurd intrinsics give): a 1 cm grid would need 4e10 columns; the
  // cells grow until the points' share of columns is left, and every point is still found.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> across(-1000.f, 1000.f);
  std::vector<Eigen::Vector3f> points;
  for (int k = 0; k < 300; ++k) points.emplace_back(across(rng), across(rng), 2.f);
  const VoxelGrid grid(points, 0.01f);
  EXPECT_LE(grid.columns(), VoxelGrid::maxColumns(points.size()));
  EXPECT_GT(grid.columns(), VoxelGrid::maxColumns(points.size()) / 1.5 / 1.5);  // not coarser
  for (std::size_t i = 0; i < points.size(); ++i) {
    bool found = false;
    grid.forEachWithin(points[i], 0.01f,
                       [&](int j, const Eigen::Vector3f&) { found |= j == int(i); });
    ASSERT_TRUE(found) << "point " << i;
  }
  // A camera's cloud keeps its cells: 2000 points within a metre at 9 cm.
  const LabelledCloud c = test::randomCloud(2000, 7, 0.5f);
  EXPECT_EQ(VoxelGrid(c.points, 0.09f).cell(), 0.09f);
}

TEST(PaperKernel, EqualsBruteForceOnRandomClouds) {
  const PaperParams p = paperParams().paper;
  const LabelledCloud X = test::randomCloud(1500, 1, 0.5f);
  Eigen::Isometry3d motion = expSE3((Vector6d() << 0.02, -0.01, 0.03, 0.02, 0.01, -0.03).finished());
  const LabelledCloud Z = test::transformed(test::randomCloud(1500, 1, 0.5f), motion.inverse());
  const auto fx = preparePaper(X, p, true), mz = preparePaper(Z, p, false);
  PaperKernel kernel(fx->cloud, mz->cloud, fx->grid, p);
  for (double ell : {0.15, 0.1, 0.05}) {
    const CrossSums& s = kernel.evaluate(Eigen::Isometry3d::Identity(), ell);
    const test::BruteForce b = test::bruteForce(X, Z, Eigen::Isometry3d::Identity(), ell, p);
    ASSERT_GT(b.nnz, 100) << "the test needs overlapping clouds";
    // Pairs within float rounding of the threshold may differ: allow a handful.
    EXPECT_NEAR(double(s.nnz), double(b.nnz), 3.0) << "ell " << ell;
    EXPECT_NEAR(s.F, b.F, 1e-4 * b.F + 3 * p.sparsification);
    EXPECT_NEAR(s.F_d2, b.F_d2, 1e-3 * b.F_d2 + 1e-5);
    EXPECT_LT((s.omega * p.omega_scale - b.omega_sum).norm(), 1e-3 * b.omega_sum.norm() + 1e-4);
    EXPECT_LT((s.v * p.v_scale - b.v_sum).norm(), 1e-3 * b.v_sum.norm() + 1e-4);
  }
}

// The default engine's kernel pass against its definition (docs/method.md §6), pair by pair in
// double: each moving point's own length-scale (ell z / ell_depth_reference) and depth noise
// along its ray (kappa), the radius and threshold tests, and the moments its H is made of.
LevelSums levelSumsByBruteForce(const LabelledCloud& X, const LabelledCloud& Z,
                                const Eigen::Isometry3d& T, double ell,
                                const CoarseToFineParams& p) {
  const double r2_unit = spatialRadius2(ell, p.sigma, p.sparsification);
  const double color_inv = 1.0 / (2.0 * p.color_ell * p.color_ell);
  LevelSums s;
  double m0 = 0.0;
  Eigen::Vector3d m1 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d m2 = Eigen::Matrix3d::Zero(), along = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < Z.size(); ++j) {
    const double z = Z.points[j].z();
    const double scale = ellScale(float(z), p), noise = p.depth_noise * z * z;
    const double l = ell * scale;
    const double kappa = 2.0 * noise * noise / (l * l + 2.0 * noise * noise);
    const double search = std::min(scale / std::sqrt(1.0 - kappa), double(kMaxEllScale));
    const Eigen::Vector3d y = T * Z.points[j].cast<double>(), ray = y.normalized();
    double a_sum = 0.0;
    Eigen::Vector3d x_sum = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < X.size(); ++i) {
      const Eigen::Vector3d d = X.points[i].cast<double>() - y;
      const double label_d2 = (X.labels[i] - Z.labels[j]).cast<double>().squaredNorm();
      const double a = p.sigma * p.sigma *
                       std::exp(-(d.squaredNorm() - kappa * d.dot(ray) * d.dot(ray)) /
                                (2.0 * l * l)) *
                       p.color_sigma * p.color_sigma * std::exp(-label_d2 * color_inv);
      if (d.squaredNorm() >= r2_unit * search * search || a < p.sparsification) continue;
      a_sum += a;
      x_sum += a * X.points[i].cast<double>();
      ++s.nnz;
    }
    s.F += a_sum;
    if (!(a_sum > 0.0)) continue;
    ++s.matched;
    const double s2 = scale * scale, wa = a_sum / s2;
    m0 += wa;
    m1 += wa * y;
    m2 += wa * y * y.transpose();
    along += wa * kappa * ray * ray.transpose();
    const Eigen::Vector3d e = (x_sum - a_sum * y) / s2;
    const Eigen::Vector3d we = e - kappa * ray * ray.dot(e);
    s.g.head<3>() += y.cross(we);
    s.g.tail<3>() += we;
  }
  s.H.topLeftCorner<3, 3>() = m2.trace() * Eigen::Matrix3d::Identity() - m2;
  s.H.topRightCorner<3, 3>() = hat(m1);
  s.H.bottomLeftCorner<3, 3>() = hat(m1).transpose();
  s.H.bottomRightCorner<3, 3>() = m0 * Eigen::Matrix3d::Identity() - along;
  return s;
}

TEST(LevelKernel, EqualsBruteForceWithLongAndShortLists) {
  CoarseToFineParams p;
  p.color_ell = 0.3;  // the fixtures' labels vary smoothly: most pairs in reach pass on colour
  const LabelledCloud X = test::randomCloud(1500, 5, 0.5f);
  const Eigen::Isometry3d motion =
      expSE3((Vector6d() << 0.01, -0.02, 0.01, 0.01, 0.02, -0.01).finished());
  const LabelledCloud Z = test::transformed(test::randomCloud(1500, 5, 0.5f), motion.inverse());
  const Eigen::Isometry3d T = expSE3((Vector6d() << 0.002, 0.0, -0.001, 0.003, -0.002, 0.001)
                                         .finished()) * motion;
  // A list per moving point of some hundreds of candidates at 50 mm, a few at 8 mm (the pass
  // sums short and long lists differently).
  for (double ell : {0.05, 0.02, 0.008}) {
    const VoxelGrid grid(X.points, gridCell(ell, p.sigma, p.sparsification));
    LevelKernel kernel(X, Z, grid, p);
    const LevelSums& s = kernel.evaluate(T, ell);
    const LevelSums b = levelSumsByBruteForce(X, Z, T, ell, p);
    ASSERT_GT(b.nnz, 1000) << "the test needs overlapping clouds";
    const double per_point = double(b.nnz) / double(Z.size());
    EXPECT_TRUE(ell > 0.01 ? per_point > 8.0 : per_point < 4.0) << ell << ": " << per_point;
    // Pairs within float rounding of a test's bound may differ: allow a handful.
    EXPECT_NEAR(double(s.nnz), double(b.nnz), 3.0) << "ell " << ell;
    EXPECT_NEAR(double(s.matched), double(b.matched), 3.0) << "ell " << ell;
    EXPECT_NEAR(s.F, b.F, 1e-4 * b.F + 3 * p.sparsification) << "ell " << ell;
    EXPECT_LT((s.g - b.g).norm(), 1e-3 * b.g.norm() + 1e-3) << "ell " << ell;
    EXPECT_LT((s.H - b.H).norm(), 1e-4 * b.H.norm()) << "ell " << ell;
  }
}

TEST(PaperKernel, KeptEntriesAreAboveTheThreshold) {
  const PaperParams p = paperParams().paper;
  const LabelledCloud X = test::randomCloud(800, 3, 0.4f);
  const auto fx = preparePaper(X, p, true), mz = preparePaper(X, p, false);
  PaperKernel kernel(fx->cloud, mz->cloud, fx->grid, p);
  const CrossSums& s = kernel.evaluate(Eigen::Isometry3d::Identity(), 0.1);
  // Every kept entry is >= threshold, so the mean is too; and self-pairs are counted.
  ASSERT_GT(s.nnz, 0);
  EXPECT_GE(s.F / double(s.nnz), p.sparsification);
  EXPECT_GE(s.nnz, 800);  // at least the diagonal
}

TEST(SelfKernel, PairsEqualBruteForce) {
  const PaperParams p = paperParams().paper;
  const LabelledCloud X = test::randomCloud(1000, 4, 0.4f);
  const auto fx = preparePaper(X, p, true);
  for (double ell : {0.15, 0.08, 0.04}) {
    const SelfSums s = selfKernelSums(*fx, ell, p);
    const test::BruteForce b = test::bruteForce(X, X, Eigen::Isometry3d::Identity(), ell, p);
    EXPECT_NEAR(double(s.nnz), double(b.nnz), 4.0);
    EXPECT_NEAR(s.sum, b.F, 1e-5 * b.F + 4 * p.sparsification);
    EXPECT_NEAR(s.sum_d2, b.F_d2, 1e-4 * b.F_d2 + 1e-6);
  }
  // Rows below first_row are dropped: with first_row = n nothing is left.
  EXPECT_EQ(selfKernelSums(*fx, 0.1, p, 1000).nnz, 0);
}

}  // namespace
}  // namespace acvo
