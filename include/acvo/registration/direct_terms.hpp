// The default engine's last-level terms (docs/method.md §6): residuals measured directly in
// the reference's images where each moving point projects. The kernel sum brings the clouds
// within a pixel or two but its width limits how finely it resolves the motion; these terms
// resolve it to a fraction of a pixel, as direct methods do:
//  - photometric: the point's grey value against the reference's (DVO, DSO);
//  - point to plane: the point against the plane of the reference's depth there
//    (projective association, as KinectFusion's ICP), weighed by how much better the depth
//    is than the depth noise the kernel assumes: full weight on exact depth (a simulator's),
//    none on a Kinect's.
// Each term learns the scale s of its residuals from them at every iteration (1.4826 times their
// median absolute value, a photometric residual counted by its squared gradient), gives each the
// variance s^2 (plus, for a grey value, its gradient squared times the 1/12 px^2 to which an
// edge's position is known) and Huber's weight beyond 2 standard deviations.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/camera.hpp"
#include "acvo/labelled_cloud.hpp"
#include "acvo/se3.hpp"

namespace acvo {

// A cloud's images as the terms read them.
struct DirectImages {
  cv::Mat intensity;  // CV_32FC1 grey levels, smoothed by a Gaussian of kSmoothing pixels
  cv::Mat gx, gy;     // CV_32FC1 its central differences (a reference's: addGradients)
  cv::Mat depth;      // CV_32FC1 metres, 0 or NaN = none (the cloud's own)
  Camera camera;
  bool empty() const { return intensity.empty() || depth.empty(); }
};

// Smoothing of the grey images (pixels, Gaussian std): rendered images sampled without
// anti-aliasing give intensity steps no sub-pixel shift can match; a Kinect's are smooth already.
constexpr double kSmoothing = 0.7;

// From the cloud's grey and depth images (empty when the cloud has none).
DirectImages directImages(const LabelledCloud& cloud);
// The intensity's derivatives, which a reference needs.
void addGradients(DirectImages& images);

// Gauss-Newton sums of 1/2 sum rho(r_j / s) for a left perturbation xi = (omega, v) of T
// (the step is H^-1 g), s the learned scale.
struct DirectSums {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  int used = 0;        // residuals summed
  double scale = 0.0;  // their learned scale (grey levels; metres per metre^2 of depth)
};

// r_j = I_ref(pi(T z_j)) - I_moving(pixel_j). Left out: points that project outside the image
// or behind the camera, points on a depth discontinuity of their own image (their grey value
// belongs to either side), and points whose depth disagrees with the reference's where they
// project (occluded there).
DirectSums photometricSums(const DirectImages& reference, const DirectImages& moving,
                           const LabelledCloud& moving_cloud, const Eigen::Isometry3d& T);

// r_j = n^T (T z_j - x) / z_j^2, x the reference's point at the pixel where T z_j projects and
// n the normal of its depth there (the same points left out). The weights fade with the learned
// scale s: (1 - s / (kPlaneFade sqrt(2) depth_noise)), none beyond; depth_noise 0 = exact depth,
// full weight.
constexpr double kPlaneFade = 0.5;
DirectSums pointToPlaneSums(const DirectImages& reference, const LabelledCloud& moving_cloud,
                            const Eigen::Isometry3d& T, double depth_noise);

}  // namespace acvo
