// The default engine (docs/method.md §6): the paper's kernel sum F, shaped for real depth
// (a Gaussian kept to 3 ell, each point's length-scale in proportion to its depth and stretched
// along its viewing ray by the depth noise) and maximised level by level, from a wide
// length-scale on a few points to the finest on all of them, by Gauss-Newton steps on the
// quadratic that minorises F at the current kernel values; at the finest level, photometric
// and point-to-plane residuals (direct_terms.hpp) add their precision to that quadratic.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "acvo/params.hpp"
#include "acvo/registration/direct_terms.hpp"
#include "acvo/registration/engine.hpp"
#include "acvo/registration/kernel.hpp"

namespace acvo {

// A cloud as this engine prepares it: its images for the direct terms (when on), and for a
// reference one search grid per level and its whole smoothed grey image.
struct CoarseToFineCloud : PreparedCloud {
  std::vector<VoxelGrid> level_grids;  // one per levelElls, built by prepareReference
  DirectImages images;
};

// Whether the last level adds direct terms to the kernel's.
bool directTerms(const CoarseToFineParams& p);

// The depth noise the plane terms' weights fade against (pointToPlaneSums, denseGrid): the
// kernel's depth_noise, or 0 (no fade: each term at its learned scale's weight) when the last
// level is led by the depth (CoarseToFineParams::depth_led), where the kernel's quadratic
// counts kDepthLedKernelShare of its weight: the best of 1, 0.5, 0.3, 0.1 and 0 on kitchen7s_dev
// and on eight rendered rooms of colour from another camera together.
double planeFadeNoise(const CoarseToFineParams& p);
constexpr double kDepthLedKernelShare = 0.3;
// The photometric term's two directions (photometricSums, reversePhotometricSums) compare the
// same two images, so their information is counted once: the reverse at this share of it, the
// forward at the rest. Over 59 rendered and real sets, RPE's geometric mean against the forward
// alone (translation / rotation): a share of 0.5 0.90 / 0.92, 0.6 0.93 / 0.95, 0.7 0.93 / 0.93,
// the reverse alone 0.96 / 0.93; at 0.5 and 0.6 a person walking slowly into the view pulls
// each frame by less than the second start's check and is followed (w62's frames 170-250:
// 0.0034 -> 0.0082 m/s), from 0.7 up it is not.
constexpr double kReverseShare = 0.7;

// The length-scales of the levels: ell_init, ell_init * ell_reduction, ... down to ell_min
// (always the last).
std::vector<double> levelElls(const CoarseToFineParams& p);

// Range-dependent length-scale (ell_depth_reference): a point at depth z uses ell * ellScale(z),
// z / reference clamped to [kMinEllScale, kMaxEllScale]; 1 when off.
constexpr float kMinEllScale = 0.5f, kMaxEllScale = 3.0f;
float ellScale(float z, const CoarseToFineParams& p);
// Whether the kernel is shaped per point (ell_depth_reference or depth_noise set).
bool perPointKernel(const CoarseToFineParams& p);

// What one kernel pass sums over the kept pairs at a transform.
struct LevelSums {
  double F = 0.0;            // sum a_ij
  std::int64_t nnz = 0;      // kept pairs
  std::int64_t matched = 0;  // moving points with at least one kept pair
  // With the kernel values a_ij held fixed, exp(-u) >= exp(-u0)(1 - (u - u0)) makes
  // sum a_ij u_ij(T) a quadratic whose decrease raises F (a minorise-maximise step, EM-ICP's).
  // H xi = g are its Gauss-Newton normal equations for a left perturbation xi = (omega, v).
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
};

// The kernel pass of one level: the pairs of fixed and moving points at a transform, each
// weighed by its own point's kernel.
class LevelKernel {
 public:
  LevelKernel(const LabelledCloud& fixed, const LabelledCloud& moving, const VoxelGrid& grid,
              const CoarseToFineParams& params);
  const LevelSums& evaluate(const Eigen::Isometry3d& T, double ell);
  const LevelSums& last() const { return sums_; }  // the last evaluate()'s
  int listBuilds() const { return lists_.builds(); }

 private:
  void shapeFor(double ell);  // the per-point kernel shapes at `ell`

  const LabelledCloud& moving_;
  CoarseToFineParams params_;
  KernelConstants k_;
  CandidateLists lists_;
  std::vector<float> scale_;  // per moving point: its length-scale / ell (ellScale)
  std::vector<float> kappa_;  // per moving point: depth-noise share along its ray
  double shaped_ell_ = -1.0;  // the ell the shapes were computed for
  std::vector<LevelSums> partial_;
  LevelSums sums_;
};

// A Gauss-Newton step (a left increment, se(3)) extended along its direction: the steps of
// the minorise-maximise iteration shrink geometrically (ratio 0.4-0.7 per iteration on real
// frames), so when `step` points the way `previous` did (cosine above 0.9) and is shorter by a
// ratio rho < 1, the rest of that geometric series is taken at once:
// step / (1 - min(rho, max_ratio)). `step` itself otherwise, and when max_ratio is 0.
Vector6d extrapolatedStep(const Vector6d& step, const Vector6d& previous, double max_ratio);

// The engine's steps as functions of values (the engine class below holds the parameters and
// what it learns of the camera from one registration to the next).
std::shared_ptr<CoarseToFineCloud> prepareCoarseToFine(LabelledCloud cloud,
                                                       const CoarseToFineParams& p,
                                                       bool as_reference);
double prepareCoarseToFineReference(CoarseToFineCloud& cloud, const CoarseToFineParams& p);
// `stages`: kCoarse the levels before the finest (none when there is one level: the guess comes
// back), kFinest the finest alone.
SolverResult alignCoarseToFine(const CoarseToFineCloud& fixed, const CoarseToFineCloud& moving,
                               const Eigen::Isometry3d& guess, const CoarseToFineParams& p,
                               AlignStages stages = AlignStages::kAll);

class CoarseToFineEngine : public RegistrationEngine {
 public:
  explicit CoarseToFineEngine(const CoarseToFineParams& params) : params_(params) {}
  std::shared_ptr<PreparedCloud> prepare(LabelledCloud cloud, bool as_reference) const override;
  double prepareReference(PreparedCloud& cloud) const override;
  using RegistrationEngine::align;
  SolverResult align(const PreparedCloud& fixed, const PreparedCloud& moving,
                     const Eigen::Isometry3d& guess, AlignStages stages) const override;
  bool staged() const override { return true; }
  bool reentrant() const override { return true; }
  // covariance_scale (-H)^-1: the information weighs each point by its own kernel, whatever
  // the number of its pairs.
  std::optional<Matrix6d> covariance(const SolverResult& s,
                                     std::size_t moving_points) const override;
  int minPoints() const override { return params_.min_points; }

 private:
  CoarseToFineParams params_;
};

}  // namespace acvo
