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

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/camera.hpp"
#include "acvo/labelled_cloud.hpp"
#include "acvo/se3.hpp"

namespace acvo {

// A cloud's images as the terms read them.
struct DirectImages {
  cv::Mat depth;  // CV_32FC1 metres, 0 or NaN = none (the cloud's own)
  Camera camera;
  // Per point of the cloud: its grey level smoothed by a Gaussian of kSmoothing pixels, and
  // whether its depth is one surface at its pixel's 4 neighbours (a grey value at a depth edge
  // belongs to either side; a point there is never used).
  std::vector<float> point_intensity;
  std::vector<std::uint8_t> one_surface;
  // A reference's whole grey image, smoothed likewise (CV_32FC1; addReferenceImages): moving
  // points are sampled in it.
  cv::Mat intensity;
  bool empty() const { return depth.empty(); }
  bool isReference() const { return !depth.empty() && !intensity.empty(); }
};

// Smoothing of the grey images (pixels, Gaussian std): rendered images sampled without
// anti-aliasing give intensity steps no sub-pixel shift can match; a Kinect's are smooth already.
constexpr double kSmoothing = 0.7;

// From the cloud's grey and depth images (empty when the cloud has none): what a moving cloud
// needs.
DirectImages directImages(const LabelledCloud& cloud);
// What a reference needs more: its whole smoothed grey image (none when `images` is empty).
void addReferenceImages(DirectImages& images, const LabelledCloud& cloud);

// Where a moving point lands in the reference: point j, its position y there and its pixel
// (u, v). Both terms read the same landings.
struct Landing {
  std::size_t j = 0;
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  double u = 0.0, v = 0.0;
};
// The points of `moving` (its images `moving_images`) that land inside the reference's image (one
// pixel in, for the derivatives and the bilinear sample), in front of the camera, on the surface
// the reference's depth shows there (not occluded), and come from one surface of their own image.
// Empty when either cloud has no images.
std::vector<Landing> landings(const DirectImages& reference, const DirectImages& moving_images,
                              const LabelledCloud& moving, const Eigen::Isometry3d& T);

// The smallest value v of the (value, weight) pairs whose weights up to v reach half of all (a
// sort's answer in linear time: quickselect on the part that holds the crossing). Reorders the
// pairs, which must not be empty. The terms' learned scales are weighted medians.
double weightedMedian(std::vector<std::pair<double, double>>& pairs);

// Gauss-Newton sums of 1/2 sum rho(r_j / s) for a left perturbation xi = (omega, v) of T
// (the step is H^-1 g), s the learned scale.
struct DirectSums {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  int used = 0;        // residuals summed
  double scale = 0.0;  // their learned scale (grey levels; metres per metre^2 of depth)
  double gain = 1.0;   // photometric: the brightness gain the residuals were measured with
};

// r_j = I_ref(pi(T z_j)) - b I_moving(pixel_j) over the landed points, b the brightness gain
// from the moving image to the reference: 1, or with `gain` brightnessGain of their grey values
// at the landed points. A camera's auto exposure scales a frame's grey levels by a few percent
// from frame to frame (DSO models it per frame, affine). A ratio of grey values hardly depends
// on how well the points are aligned, where a regression of one image on the other would shrink
// towards 0 while they are not; the median leaves out the points that another surface hides.
DirectSums photometricSums(const DirectImages& reference, const DirectImages& moving_images,
                           const LabelledCloud& moving, const std::vector<Landing>& landed,
                           bool gain = false);

// The median of reference / moving over (reference, moving) grey-value pairs that neither
// image saturates (both under kSaturated) and whose moving value is at least kDark (a ratio of
// noise below it). 1 when fewer than kMinGainPairs such pairs remain, or when the median is
// outside [1 / kMaxGain, kMaxGain] (another scene, not another exposure).
constexpr float kSaturated = 250.0f;
constexpr float kDark = 10.0f;
constexpr std::size_t kMinGainPairs = 30;
constexpr double kMaxGain = 2.0;
double brightnessGain(const std::vector<std::pair<float, float>>& grey_pairs);

// r_j = n^T (T z_j - x) / z_j^2, x the reference's point at the pixel where T z_j projects and
// n the normal of its depth there, over the landed points where the reference's surface does not
// fold. The weights fade with the learned scale s: (1 - s / (kPlaneFade sqrt(2) depth_noise)),
// none beyond; depth_noise 0 = exact depth, full weight.
constexpr double kPlaneFade = 0.5;
DirectSums pointToPlaneSums(const DirectImages& reference, const std::vector<Landing>& landed,
                            double depth_noise);

}  // namespace acvo
