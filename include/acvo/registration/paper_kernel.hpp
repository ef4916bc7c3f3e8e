// The paper engine's per-iteration sums (docs/method.md §2-§4): the cross kernel A = K(X, T Z)
// with its sparsified pairs, the ascent direction (omega, v), the 4th-order step-size sums B..E
// and the curvature at the optimum; and the self-kernel sums of one cloud for the length-scale
// update. Split from the iteration's control flow (paper.hpp) so that each formula can be
// tested on its own.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "acvo/params.hpp"
#include "acvo/registration/engine.hpp"
#include "acvo/registration/kernel.hpp"
#include "acvo/math/se3.hpp"

namespace acvo {

// A pair of distinct points of one cloud with their squared distance and colour factor.
struct SelfPair {
  int i = 0, j = 0;  // i < j
  float d2 = 0.0f;
  float color = 0.0f;
};

// A cloud as the paper engine prepares it: its search grid and self-kernel pairs, once per
// frame (the self-kernel of frame k is the fixed self-kernel of frame k+1); a reference needs
// nothing more.
struct PaperCloud : PreparedCloud {
  VoxelGrid grid;         // cell = the search radius at the largest length-scale
  std::vector<SelfPair> self_pairs;  // all pairs within that radius that can pass the threshold
  // The same pairs' d2 and colour factors as arrays, for vectorised sums per iteration.
  Eigen::ArrayXf self_d2, self_color;
};

// The largest spatial length-scale the engine may use with these parameters.
double largestEll(const PaperParams& params);

struct CrossSums {
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();  // (1/c) sum a (x cross y)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();      // (1/d) sum a (y - x)
  double F = 0.0;            // sum a_ij (the objective, also <f_X, h.f_Z>)
  double F_d2 = 0.0;         // sum a_ij |x_i - y_j|^2 (length-scale gradient term)
  std::int64_t nnz = 0;      // kept pairs
  std::int64_t matched = 0;  // moving points with at least one kept pair
};

struct StepSums {
  double B = 0.0, C = 0.0, D = 0.0, E = 0.0;
};

// Self-kernel sums of one cloud at a length-scale: sum a, sum a d^2 and the number of kept
// entries, over ordered pairs including i = j. Rows below `first_row` are left out of the sums
// and of nnz (the authors' code leaves them out of its Ayy sum); nnz_all counts every row.
struct SelfSums {
  double sum = 0.0;
  double sum_d2 = 0.0;
  std::int64_t nnz = 0;
  std::int64_t nnz_all = 0;
};
SelfSums selfKernelSums(const PaperCloud& cloud, double ell, const PaperParams& params,
                        int first_row = 0);

class PaperKernel {
 public:
  // `grid` indexes the fixed cloud's points; its cell must be at least the largest search
  // radius used.
  PaperKernel(const LabelledCloud& fixed, const LabelledCloud& moving, const VoxelGrid& grid,
              const PaperParams& params);

  // Finds the kept pairs at transform T and length-scale ell and accumulates their sums.
  // The pairs are kept for stepSums() and curvature() until the next call.
  const CrossSums& evaluate(const Eigen::Isometry3d& T, double ell);

  // B..E of the 4th-order expansion of F along y(t) = exp(-t xi^) y, xi = (omega, v), over the
  // pairs of the last evaluate().
  StepSums stepSums(const Eigen::Vector3d& omega, const Eigen::Vector3d& v) const;

  // d^2 F / d xi^2 for a left perturbation y -> exp(xi^) y, xi = (omega, v), at the last
  // evaluate() (Gauss-Newton form: the second derivative of exp itself is left out).
  Matrix6d curvature() const;

  const CrossSums& sums() const { return sums_; }
  int listBuilds() const { return lists_.builds(); }

 private:
  struct Pair {
    int i;
    float a;
  };
  // The kept pairs of the last evaluate(), per chunk of moving points.
  struct ChunkPairs {
    std::vector<Pair> pairs;
    std::vector<int> end;  // per moving point of the chunk: end index into pairs
    CrossSums sums;
  };

  const LabelledCloud& fixed_;
  const LabelledCloud& moving_;
  PaperParams params_;
  KernelConstants k_;
  CandidateLists lists_;
  double ell_ = 0.0;
  std::vector<Eigen::Vector3f> y_;  // transformed moving points
  std::vector<ChunkPairs> chunks_;
  CrossSums sums_;
};

}  // namespace acvo
