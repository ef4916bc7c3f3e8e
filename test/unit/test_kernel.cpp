// Kernel, sparsification and neighbour structures (docs/method.md §2, §5).
#include <gtest/gtest.h>

#include "acvo/registration/kernel.hpp"
#include "acvo/registration/paper.hpp"
#include "acvo/registration/paper_kernel.hpp"
#include "acvo/se3.hpp"
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
