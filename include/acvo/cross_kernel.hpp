// The per-iteration work of the solver: the cross kernel A = K(X, T Z) with its sparsified pairs,
// the ascent direction (omega, v), the 4th-order step-size sums B..E, the length-scale terms and
// the curvature at the optimum; plus the self-kernel sums of one cloud. Split from the solver's
// control flow so that each formula can be tested on its own (docs/method.md §2-§4).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "acvo/kernel.hpp"
#include "acvo/params.hpp"
#include "acvo/se3.hpp"

namespace acvo {

struct CrossSums {
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();  // (1/c) sum a (x cross y)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();      // (1/d) sum a (y - x)
  double F = 0.0;         // sum a_ij (the objective, also <f_X, h.f_Z>)
  double F_d2 = 0.0;      // sum a_ij |x_i - y_j|^2 (length-scale gradient term)
  std::int64_t nnz = 0;   // kept pairs
  std::int64_t matched = 0;  // moving points with at least one kept pair
  // coarse_to_fine's step: with the kernel values a_ij held fixed, exp(-u) >= exp(-u0)(1 - (u -
  // u0)) makes sum a_ij u_ij(T) a quadratic whose decrease raises F (a minorise-maximise
  // step, EM-ICP's). gn_H xi = gn_g are its Gauss-Newton normal equations for a left
  // perturbation xi = (omega, v) of T.
  Matrix6d gn_H = Matrix6d::Zero();
  Vector6d gn_g = Vector6d::Zero();
};

struct StepSums {
  double B = 0.0, C = 0.0, D = 0.0, E = 0.0;
};

// Self-kernel sums of one cloud at a length-scale: sum a, sum a d^2, number of kept entries,
// over ordered pairs including i = j. Rows below `first_row` are left out (the authors' code
// drops them for Ayy; 0 keeps everything).
struct SelfSums {
  double sum = 0.0;
  double sum_d2 = 0.0;
  std::int64_t nnz = 0;
};
SelfSums selfKernelSums(const PreparedCloud& cloud, double ell, const SolverParams& params,
                        int first_row = 0);

class CrossKernel {
 public:
  // `grid` indexes the fixed cloud's points; its cell must be at least the largest search
  // radius used (default: the fixed cloud's own grid).
  CrossKernel(const PreparedCloud& fixed, const PreparedCloud& moving, const SolverParams& params,
              const VoxelGrid* grid = nullptr);

  // Finds the kept pairs at transform T and length-scale ell and accumulates their sums.
  // The pairs are kept for stepSums() and curvature() until the next call.
  const CrossSums& evaluate(const Eigen::Isometry3d& T, double ell);

  // B..E of the 4th-order expansion of F along y(t) = exp(-t xi^) y, xi = (omega, v), over the
  // pairs of the last evaluate().
  StepSums stepSums(const Eigen::Vector3d& omega, const Eigen::Vector3d& v) const;

  // d^2 F / d xi^2 for a left perturbation y -> exp(xi^) y, xi = (omega, v), at the last
  // evaluate() (Gauss-Newton form: the second derivative of exp itself is left out).
  Eigen::Matrix<double, 6, 6> curvature() const;

  const CrossSums& sums() const { return sums_; }

 private:
  struct Pair {
    int i;
    float a;
  };
  // Work and results for a fixed range of moving points (the unit of parallelism).
  struct Chunk {
    // Candidate fixed points of each moving point: every fixed point within the list radius of
    // where the moving point was when the lists were built, whose colour factor lets it pass
    // the threshold at distance 0. Colour does not depend on T: its factor is cached here.
    std::vector<int> cand_end;      // per moving point of the chunk: end index into cand_*
    std::vector<int> cand_i;
    std::vector<float> cand_color;  // sigma_c^2 exp(-|f_i - g_j|^2 / 2 l_c^2)
    // Copies of the candidates' coordinates, contiguous per moving point: the kernel pass runs
    // over them with vector instructions instead of gathering fixed points by index.
    std::vector<float> cand_x, cand_y, cand_z;
    Eigen::ArrayXf scratch_d2, scratch_a;  // per-point work buffers (largest list of the chunk)
    std::vector<Pair> pairs;        // kept pairs of the last evaluate()
    std::vector<int> pair_end;      // per moving point of the chunk: end index into pairs
    CrossSums sums;
  };

  // Rebuilds the candidate lists around the moving points placed by T, for radius `radius`.
  void buildCandidates(const Eigen::Isometry3d& T, float radius);

  const PreparedCloud& fixed_;
  const PreparedCloud& moving_;
  const VoxelGrid& grid_;
  SolverParams params_;
  double ell_ = 0.0;
  std::vector<Eigen::Vector3f> y_;  // transformed moving points
  std::vector<float> scale_;        // per moving point: its length-scale / ell (ellScale)
  std::vector<float> search_scale_;  // per moving point: its search radius / the unit radius
  std::vector<float> kappa_;        // per moving point: depth-noise share along its ray
  float min_scale_ = 1.0f;
  double scale_ell_ = -1.0;         // the ell scale_ was computed for
  std::vector<Chunk> chunks_;
  CrossSums sums_;
  // Candidate lists stay valid while every moving point stays within list_radius_ - r of where
  // it was at list_T_ (r: the current search radius).
  bool lists_valid_ = false;
  Eigen::Isometry3d list_T_ = Eigen::Isometry3d::Identity();
  float list_radius_ = 0.0f;
  int list_builds_ = 0;

 public:
  int candidateListBuilds() const { return list_builds_; }
};

}  // namespace acvo
