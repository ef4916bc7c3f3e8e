// The default engine's last-level terms (docs/method.md §6): residuals measured directly in
// the reference's images where each moving point projects. The kernel sum brings the clouds
// within a pixel or two but its width limits how finely it resolves the motion; these terms
// resolve it to a fraction of a pixel, as direct methods do:
//  - photometric: the point's grey value against the reference's (DVO, DSO), and reversed,
//    each reference point's grey value against the moving image where it lands (the direction
//    DVO and DSO warp in: a keyframe's points into the new frame); the engine counts the two
//    as one term, the reverse at kReverseShare of its weight (coarse_to_fine.hpp);
//  - point to plane: the point against the plane of the reference's depth there
//    (projective association, as KinectFusion's ICP), weighed by how much better the depth
//    is than the depth noise the kernel assumes: full weight on exact depth (a simulator's),
//    none on a Kinect's;
//  - dense point to plane: the same for the moving depth on a grid of pixels, each point and
//    each plane from a window's mean, where averaging makes the depth precise: noise drawn
//    per pixel (a simulator's) or none (denseGrid).
// Each term learns the scale s of its residuals from them at every iteration (1.4826 times their
// median absolute value, a photometric residual counted by its squared gradient), gives each the
// variance s^2 (plus, for a grey value, its gradient squared times the 1/12 px^2 to which an
// edge's position is known) and Tukey's biweight to 8 standard deviations: a residual beyond
// them (a person crossing the view) no longer pulls.
// Implemented in src/core/registration, one file per part: direct_images.cpp (images, landings),
// depth_grid.cpp, brightness.cpp, motion_blur.cpp, photometric.cpp and point_to_plane.cpp.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/cloud/camera.hpp"
#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/math/se3.hpp"

namespace acvo {

// The depth of a frame on a grid of pixels, for the dense point-to-plane term. Each point is the
// mean of the (2 kGridWindow + 1)^2 window around a grid pixel, over the pixels of its surface
// (at least half the window). Averaging n pixels divides independent noise by sqrt(n) and
// does nothing to noise that neighbours share; a real structured-light sensor's comes in blobs,
// a simulator's is drawn per pixel. Both are told apart on the frame itself, from the twist
// z00 - z01 - z10 + z11 (blind to any plane) of single pixels (t) and of the four 3x3 quarter
// means of each window (T): independent noise gives
// var(t) = 9 var(T), noise in blobs var(t) << 9 var(T).
struct DepthGrid {
  std::vector<Eigen::Vector3d> points;  // the window means, camera frame
  // var(t) / (9 var(T)), in [0, 1], each variance as the mean of the smallest 80% of the
  // squares (a window across a fold twists by its shape): about 0.9 for noise drawn per pixel,
  // 0-0.12 on real Kinect frames and on rendered noise in 3-px blobs.
  double independence = 0.0;
  // sqrt(9 var(T) / 4) / z^2: the standard deviation of a pixel's noise that a window does not
  // average away, in units of depth_noise (1/m) (var(T) from the trimmed mean of T^2, 0.438 of
  // the variance for Gaussian noise).
  double shared_noise = 0.0;
  // The weight of the term: the independence where it is at least kMinIndependence, else how
  // far the shared noise is under the modelled depth noise (1 - shared_noise / (kPlaneFade
  // depth_noise), as the sparse term's fade): exact depth, full weight.
  double weight = 0.0;
  int stride = 0;  // pixels between the points: kGridStride, or kExactGridStride; 0 without points
  bool empty() const { return points.empty(); }
};
constexpr int kGridStride = 10;  // pixels between grid points (3072 on a 640x480 image)
// ... where the depth is exact, its shared noise under kExactDepthNoise times the modelled depth
// noise (rendered: at most 0.00006 exact, at least 0.0017 with noise per pixel or in blobs;
// a Kinect's 0.002): 12288 points. No noise to average, every point is a constraint, as each of
// ICPOdometry's pixels is.
constexpr int kExactGridStride = 5;  // CoarseToFineParams::exact_depth_grid_stride's default
constexpr double kExactDepthNoise = 0.1;
constexpr int kGridWindow = 3;   // a window's half size: 7x7 pixels
constexpr int kNormalReach = 4;  // pixels between a plane's window means
constexpr double kMinIndependence = 0.5;

// A cloud's images as the terms read them.
struct DirectImages {
  cv::Mat depth;  // CV_32FC1 metres, 0 or NaN = none (the cloud's own)
  Camera camera;
  // Per point of the cloud: its grey level smoothed by a Gaussian of kSmoothing pixels, and
  // whether its depth is one surface at its pixel's 4 neighbours and along its motion blur
  // (LabelledCloud::blur_motion): a grey value at a depth edge, or blurred over one, belongs to
  // either side; such a point is never used.
  std::vector<float> point_intensity;
  std::vector<std::uint8_t> one_surface;
  // The whole grey image, smoothed likewise (CV_32FC1): a reference's (addReferenceImages),
  // where moving points are sampled, and a moving cloud's where the reverse photometric term
  // samples the reference's points in it (directImages' whole_image).
  cv::Mat intensity;
  // The depth on a grid of pixels (denseGrid; empty when the dense term is off for this depth)
  // and, for a reference with a grid, the sums of its points (x, y, z, 1) over the 7x7 window
  // around each pixel (CV_32FC4): a window's mean point in one read.
  DepthGrid grid;
  cv::Mat point_sums;
  bool reference = false;  // addReferenceImages was called
  double smoothing = 0.0;  // the Gaussian std (px) the grey values were smoothed by
  bool empty() const { return depth.empty(); }
  bool isReference() const { return reference && !depth.empty() && !intensity.empty(); }
};

// Smoothing of the grey images (pixels, Gaussian std; CoarseToFineParams::grey_smoothing's
// default): rendered images sampled without anti-aliasing give intensity steps no sub-pixel
// shift can match; a Kinect's are smooth already.
constexpr double kSmoothing = 0.7;
// Tukey's biweight cut, in standard deviations (CoarseToFineParams::tukey_sigmas' default).
constexpr double kTukeySigmas = 8.0;

// From the cloud's grey and depth images (empty when the cloud has none): what a moving cloud
// needs; with `dense` the depth grid too, unless the cloud's depth was taken at another instant
// than its colour (LabelledCloud::depth_of_another_instant) or the grid's weight (for
// depth_noise) is 0; with `whole_image` the whole smoothed grey image (the reverse photometric
// term's).
DirectImages directImages(const LabelledCloud& cloud, bool dense = false, double depth_noise = 0.0,
                          bool whole_image = false, double smoothing = kSmoothing,
                          int exact_grid_stride = kExactGridStride);
// The depth grid of a depth image (CV_32FC1 metres, 0 or NaN = none), with its weight for the
// modelled depth_noise; no points when the weight is 0.
DepthGrid denseGrid(const cv::Mat& depth, const Camera& camera, double depth_noise,
                    int exact_grid_stride = kExactGridStride);
// What a reference needs more: its whole smoothed grey image and, when it has a depth grid, its
// points' window sums (none when `images` is empty).
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

// How a point's grey value in the moving image compares with the reference's where it lands:
// I_ref(q) = gain exp(vignetting (rho(q) - rho(p))) I_moving(p), for a point seen at pixel p in
// the moving image and at q in the reference, rho = ((u - cx) / fx)^2 + ((v - cy) / fy)^2.
// A camera's auto exposure sets the gain from frame to frame; its lens darkens the image
// towards the corners (vignetting < 0: exp(vignetting rho), the falloff of the camera itself,
// the same in both images).
struct Brightness {
  double gain = 1.0;
  double vignetting = 0.0;
  double at(double shift) const {
    return vignetting == 0.0 ? gain : gain * std::exp(vignetting * shift);
  }
};

// Gauss-Newton sums of 1/2 sum rho(r_j / s) for a left perturbation xi = (omega, v) of T
// (the step is H^-1 g), s the learned scale.
struct DirectSums {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  int used = 0;        // residuals summed
  double scale = 0.0;  // their learned scale (grey levels; metres per metre^2 of depth)
  Brightness brightness;  // photometric: the brightness the residuals were measured at
};

// A landed point's grey values as brightnessOf reads them.
struct GreyPair {
  float reference = 0.0f;  // I_ref(q)
  float moving = 0.0f;     // I_moving(p)
  float shift = 0.0f;      // rho(q) - rho(p)
  float flat = 1.0f;       // 1 / (1 + |grad I_ref(q)|^2 / kFlatGradient^2)
};

// The photometric residuals' variance is s^2 + |grad I|^2 p2, s their learned scale and p2 the
// variance of where an intensity edge lies (DSO's gradient-dependent weight, its constant
// measured): a pixel's quantisation, kEdgePosition2 = 1/12 px^2.
constexpr double kEdgePosition2 = 1.0 / 12.0;  // px^2

// r_j = I_ref(pi(T z_j)) - B_j I_moving(pixel_j) over the landed points, B_j the brightness
// from the moving image to the reference at that point: 1, or brightnessOf their grey values
// (`gain`, `vignetting`); `edge_position2` the p2 of their variance. DSO models the same (an
// affine brightness per frame, a vignetting calibrated offline); here both are measured at
// every iteration from the points compared.
DirectSums photometricSums(const DirectImages& reference, const DirectImages& moving_images,
                           const LabelledCloud& moving, const std::vector<Landing>& landed,
                           bool gain = false, bool vignetting = false,
                           double edge_position2 = kEdgePosition2,
                           double tukey_sigmas = kTukeySigmas);

// The reverse direction, r_i = I_ref(pixel_i) - B_i I_moving(pi(T^-1 x_i)) over the reference's
// points x_i that land in the moving image (moving_images.intensity, from directImages'
// whole_image; none without it) on the surface the moving depth has there: one surface at the
// landing's 4 neighbours and along the moving cloud's motion blur, as a moving point must be at
// its own pixel. B_i is the brightness the forward term measured (reference = B moving), at the
// shift rho(pixel_i) - rho(landing). The same left perturbation of T as the forward term's.
DirectSums reversePhotometricSums(const DirectImages& reference,
                                  const LabelledCloud& reference_cloud,
                                  const DirectImages& moving_images,
                                  const LabelledCloud& moving_cloud, const Eigen::Isometry3d& T,
                                  const Brightness& brightness,
                                  double edge_position2 = kEdgePosition2,
                                  double tukey_sigmas = kTukeySigmas);

// The brightness of the pairs (at most kBrightnessPairs of them, evenly spaced) that neither
// image saturates (both under kSaturated) and that are not dark (both at least kDark: a ratio
// of noise below it):
//  - gain: the median of reference / moving. A ratio of grey values hardly depends on how well
//    the points are aligned yet, where a regression of one image on the other would shrink
//    towards 0 while they are not; the median leaves out the points another surface hides.
//  - vignetting: the least-absolute-deviations slope of log(reference / moving) - log(gain)
//    against the shift (the median of the pairs' slopes, weighted by |shift| and by flat: a
//    grey value at an edge changes with a sub-pixel misalignment, one on a slope does not),
//    within [kMinVignetting, kMaxVignetting]; then the gain again as the median of what the
//    vignetting leaves, kBrightnessRounds times over (the least-absolute-deviations line by
//    coordinate descent: pairs that another surface hides on one side only pull the first
//    median, and rounds undo it).
// What is not asked for stays as in Brightness{} (1, 0); both are 1 and 0 when fewer than
// kMinGainPairs pairs remain or when the gain is outside [1 / kMaxGain, kMaxGain] (another
// scene, not another exposure).
constexpr float kSaturated = 250.0f;
constexpr float kDark = 10.0f;
constexpr std::size_t kMinGainPairs = 30;
constexpr double kMaxGain = 2.0;
constexpr double kMinVignetting = -3.0, kMaxVignetting = 1.0;
constexpr double kFlatGradient = 8.0;  // grey levels per pixel
// At most this many pairs are read (every k-th of more): a median of a thousand is known to a
// few hundredths of its spread, and reading every landed point cost 4% of a frame.
constexpr std::size_t kBrightnessPairs = 1024;
constexpr int kBrightnessRounds = 4;
Brightness brightnessOf(const std::vector<GreyPair>& pairs, bool gain, bool vignetting);

// r_j = n^T (T z_j - x) / z_j^2, x the reference's point at the pixel where T z_j projects and
// n the normal of its depth there, over the landed points where the reference's surface does not
// fold. The weights fade with the learned scale s: (1 - s / (kPlaneFade sqrt(2) depth_noise)),
// none beyond; depth_noise 0 = exact depth, full weight.
constexpr double kPlaneFade = 0.5;
// The reference's plane at the pixels where the moving points landed last, per moving point:
// a level's iterations land most points at the same pixels again, and their planes (five
// back-projections and two fold tests each) need not be found again. One per registration of
// a moving cloud to one reference.
class PlaneMemo {
 public:
  struct Plane {
    int pixel = -1;  // v * cols + u; -1: none yet
    bool found = false;  // one surface there, and no fold
    Eigen::Vector3d x = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
  };
  Plane& of(std::size_t j) {
    if (planes_.size() <= j) planes_.resize(j + 1);
    return planes_[j];
  }

 private:
  std::vector<Plane> planes_;
};
DirectSums pointToPlaneSums(const DirectImages& reference, const std::vector<Landing>& landed,
                            double depth_noise, PlaneMemo* memo = nullptr,
                            double tukey_sigmas = kTukeySigmas);
// The dense term's weight between a reference and a moving cloud: the moving grid's, 0 when
// either has no grid (the reference's window sums are built only with its own grid).
double denseWeight(const DirectImages& reference, const DirectImages& moving_images);
// r_k = n^T (T g_k - x) / z_k^2 for the moving grid's points g_k (DepthGrid), x the mean point
// of the reference's window where T g_k projects and n the normal from the means kNormalReach
// pixels to each side, where the reference's surface does not fold there; weighed by
// denseWeight. Nothing where that is 0.
DirectSums densePlaneSums(const DirectImages& reference, const DirectImages& moving_images,
                          const Eigen::Isometry3d& T, double tukey_sigmas = kTukeySigmas);

}  // namespace acvo
