// Frame-to-frame odometry: owns the previous cloud, builds each cloud once, guesses the
// motion (constant velocity or identity), registers, composes the pose, judges tracking.
#pragma once

#include <memory>
#include <optional>

#include <Eigen/Geometry>

#include "acvo/frame.hpp"
#include "acvo/labelled_cloud.hpp"
#include "acvo/params.hpp"
#include "acvo/solver.hpp"

namespace acvo {

enum class Tracking { kOk, kHard, kLost, kFirstFrame, kBadFrame };
std::string toString(Tracking t);

struct OdometryResult {
  Tracking tracking = Tracking::kBadFrame;
  std::string message;  // why tracking is hard / lost / the frame is bad; empty when ok
  // Camera pose of this frame in the odometry frame (the first frame's camera, or the pose
  // given to reset()), optical-frame convention.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // Motion from this frame's camera to the previous frame's camera (T: current -> previous).
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  // Covariance of the relative motion `motion` for a left perturbation motion -> exp(xi^) motion,
  // xi = (rotation x y z, translation x y z), expressed in the previous camera's frame; rad^2 and
  // m^2. Model: covariance_scale * (-H)^-1 with H the curvature of the objective at the optimum
  // (SolverResult::hessian; the paper's policies also multiply by nnz / moving points);
  // multiplied by 10 when tracking is hard; 1e6 on the diagonal when lost.
  Eigen::Matrix<double, 6, 6> motion_covariance = Eigen::Matrix<double, 6, 6>::Identity();
  SolverResult solver;
  std::size_t fixed_points = 0;
  std::size_t moving_points = 0;
  double ms_cloud = 0.0;         // building this frame's cloud (selection + labels + self-kernel)
  double ms_prepare = 0.0;       // of which: search grid + self-kernel pairs
  double ms_registration = 0.0;  // the solver
  CloudStats cloud_stats;
};

// Tracking judgement of a registered frame:
//  - lost: the solver failed (too few points, not finite), fewer than lost_matched_fraction of
//    the frame's points found a kernel partner (nothing in common: noise, another view), or the
//    motion exceeds max_translation / max_rotation per frame. A low overlap alone is not lost:
//    a fast motion registered from the part of the view it keeps is kept. The pose is kept and
//    the motion prior is dropped. The reference is re-seeded from this frame, except from a
//    frame with too few points (blank) and from a first lost frame that has next to nothing in
//    common with it (matched below lost_matched_fraction / 5: noise): then the next frame is
//    registered against the last good one.
//  - hard: matched below hard_matched_fraction, iteration cap reached, or (adaptive policy)
//    the length-scale reached its upper bound at least hard_ell_reductions times.
//  - ok otherwise.
class Odometry {
 public:
  explicit Odometry(const Params& params = Params());
  ~Odometry();
  Odometry(Odometry&&) noexcept;
  Odometry& operator=(Odometry&&) noexcept;

  // Processes one frame. A frame with a problem (Frame::problem()) is rejected with
  // Tracking::kBadFrame and does not change the state.
  OdometryResult process(const Frame& frame);

  // Drops the reference cloud; the next frame starts again from `pose`.
  void reset(const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity());

  const Eigen::Isometry3d& pose() const { return pose_; }
  const Params& params() const { return params_; }
  // The cloud of the last processed frame (the current reference), if any.
  const LabelledCloud* lastCloud() const;

 private:
  Params params_;
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();  // last relative motion
  double velocity_interval_ = 0.0;  // s between the two frames of velocity_ (0: unknown)
  std::optional<PreparedCloud> reference_;
  bool last_lost_ = false;  // the previous frame was lost (see the judgement above)
  struct Arena;  // the thread pool the solver runs in (odometry.threads)
  std::unique_ptr<Arena> arena_;
};

}  // namespace acvo
