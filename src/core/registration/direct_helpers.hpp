// The small pieces the last-level terms share (direct_images.cpp, motion_blur.cpp,
// photometric.cpp, point_to_plane.cpp, depth_grid.cpp): which depths are one surface, the
// bilinear grey sample with its gradient, the projection's derivative, and the Gauss-Newton sums
// of a term's residuals with its learned scale. Internal to src/core/registration.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "acvo/math/order_statistics.hpp"
#include "acvo/registration/direct_terms.hpp"

namespace acvo::direct {

// Tukey's biweight, (1 - (r / (c sd))^2)^2 and none beyond c standard deviations (c =
// tukey_sigmas; 1 everywhere for c = 0): a residual far outside its term's own scale (a person
// crossing the view, an occlusion) stops pulling.
inline double tukeyWeight(double r, double sd, double tukey_sigmas) {
  if (!(tukey_sigmas > 0.0)) return 1.0;
  const double u = r / (tukey_sigmas * sd);
  const double v = 1.0 - u * u;
  return v > 0.0 ? v * v : 0.0;
}
// The learned scales stop here: a grey level (the 8-bit quantisation); 1e-5 m at 1 m of depth
// (a 16-bit PNG at 5000 per metre quantises to 2e-4 m).
constexpr double kMinIntensityScale = 1.0;
constexpr double kMinPlaneScale = 1e-5;
// Depths that differ by more than this fraction belong to different surfaces.
constexpr float kSameSurface = 0.05f;

// How much depth whose noise is `scale` is worth against the modelled noise `modelled`: 1 - scale /
// (kPlaneFade modelled), none beyond; full weight when the model says the depth is exact (0).
inline double planeFade(double scale, double modelled) {
  return modelled > 0.0 ? std::clamp(1.0 - scale / (kPlaneFade * modelled), 0.0, 1.0) : 1.0;
}

inline bool sameSurface(float a, float b) {
  return a > 0.0f && b > 0.0f && std::abs(a - b) <= kSameSurface * std::min(a, b);
}

// The pixel nearest to coordinate x > -0.5 (std::lround's answer there, halves rounded up): the
// terms round a few projections per point and iteration, and std::lround is a call into libm
// where std::floor is one instruction (SSE4.1, in the build's x86-64-v2).
inline int nearestPixel(double x) { return int(std::floor(x + 0.5)); }

// Whether the depth around pixel p (its 4 neighbours) is one surface with depth z.
inline bool smoothAround(const cv::Mat& depth, const cv::Point& p, float z) {
  if (p.x < 1 || p.y < 1 || p.x + 1 >= depth.cols || p.y + 1 >= depth.rows) return false;
  return sameSurface(depth.at<float>(p.y, p.x - 1), z) &&
         sameSurface(depth.at<float>(p.y, p.x + 1), z) &&
         sameSurface(depth.at<float>(p.y - 1, p.x), z) &&
         sameSurface(depth.at<float>(p.y + 1, p.x), z);
}

// Whether the depth along the blur of point x of the cloud's frame, seen at pixel p at depth z
// (its image motion over cloud.blur_motion, centred on p, a pixel more at each end), is x's own
// surface: a colour edge blurred over a depth edge gives the points near it the other surface's
// colour.
bool oneSurfaceAlongBlur(const LabelledCloud& cloud, const Eigen::Vector3d& x, const cv::Point& p,
                         float z);  // motion_blur.cpp

// Whether the surface goes on straight from step a to step b (within kFold).
constexpr double kFold = 0.2;  // sine of the largest turn, about 12 deg
inline bool straight(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return a.cross(b).norm() <= kFold * a.norm() * b.norm();
}

// A grey image's bilinear sample at (u, v) in [1, cols - 2) x [1, rows - 2), and the bilinear
// sample there of its central differences 0.5 (I[x+1] - I[x-1]) and 0.5 (I[y+1] - I[y-1]), from
// the 4x4 pixels around it: a few thousand samples per iteration, where differentiating a
// reference's whole image (cv::Sobel) cost a few milliseconds per keyframe.
struct GreySample {
  float value = 0.0f;
  Eigen::Vector2d gradient = Eigen::Vector2d::Zero();
};
inline GreySample bilinearWithGradient(const cv::Mat& image, double u, double v) {
  const int x = int(u), y = int(v);
  const float a = float(u - x), b = float(v - y);
  const float* rm = image.ptr<float>(y - 1) + x;
  const float* r0 = image.ptr<float>(y) + x;
  const float* r1 = image.ptr<float>(y + 1) + x;
  const float* r2 = image.ptr<float>(y + 2) + x;
  auto across = [a](const float* r) { return (1.0f - a) * (r[1] - r[-1]) + a * (r[2] - r[0]); };
  auto down = [a](const float* lo, const float* hi) {
    return (1.0f - a) * (hi[0] - lo[0]) + a * (hi[1] - lo[1]);
  };
  GreySample s;
  s.value = (1.0f - b) * ((1.0f - a) * r0[0] + a * r0[1]) + b * ((1.0f - a) * r1[0] + a * r1[1]);
  s.gradient = {0.5 * double((1.0f - b) * across(r0) + b * across(r1)),
                0.5 * double((1.0f - b) * down(rm, r1) + b * down(r0, r2))};
  return s;
}

// The terms read the images at a few thousand scattered pixels per iteration, and the images
// (1.2 MB each at 640x480) live in the last-level cache at best: a sample waited on its rows.
// The loops ask for the rows of the sample kAhead landings on first (a compiler builtin: GCC and
// Clang, every target; a hint with no effect on results).
constexpr std::size_t kAhead = 8;
inline void prefetchAround(const cv::Mat& image, int x, int y, int rows_before, int rows_after) {
  for (int r = -rows_before; r <= rows_after; ++r) {
    const float* row = image.ptr<float>(y + r);
    __builtin_prefetch(row + x - 1);
    __builtin_prefetch(row + x + 2);
  }
}

// The squared distance of pixel (u, v)'s ray from the optical axis, on the plane z = 1: what a
// lens's vignetting depends on (Brightness::at reads the difference between two pixels').
inline double rho(const Camera& cam, double u, double v) {
  const double x = (u - cam.cx) / cam.fx, y = (v - cam.cy) / cam.fy;
  return x * x + y * y;
}

// An image gradient (gu, gv) at the projection of camera point y, carried to y:
// [gu gv] d pi / d y.
inline Eigen::Vector3d gradientAtPoint(const Camera& cam, const Eigen::Vector2d& grad,
                                       const Eigen::Vector3d& y) {
  const double gu = grad.x(), gv = grad.y();
  const double iz = 1.0 / y.z();
  return {gu * cam.fx * iz, gv * cam.fy * iz,
          -(gu * cam.fx * y.x() + gv * cam.fy * y.y()) * iz * iz};
}

// One residual, its Jacobian for a left perturbation, and how much it says about the motion
// (its squared sensitivity to a shift: the squared intensity gradient, or 1).
struct Residual {
  double r;
  Vector6d J;
  double say = 1.0;
};

// Learns the scale s of the residuals (at least min_scale): 1.4826 times their median absolute
// value, each residual counted by its say, so that the many that carry nothing (grey values on
// a flat colour) do not set the scale of the few that carry the motion. Then sums them, each
// with the variance s^2 + say * position_var, weighed down by Tukey's biweight in its standard
// deviations, and the whole times weight(s).
template <typename Weight>
DirectSums sumsOf(std::vector<Residual>& residuals, double min_scale, double position_var,
                  double tukey_sigmas, Weight&& weight) {
  DirectSums s;
  if (residuals.empty()) return s;
  std::vector<std::pair<double, double>> by_size;
  by_size.reserve(residuals.size());
  for (const Residual& q : residuals) by_size.emplace_back(std::abs(q.r), q.say);
  const double median = weightedMedian(by_size);
  s.scale = std::max(1.4826 * median, min_scale);
  const double factor = weight(s.scale);
  if (!(factor > 0.0)) return s;
  for (const Residual& q : residuals) {
    const double var = s.scale * s.scale + q.say * position_var;
    const double w = factor / var * tukeyWeight(q.r, std::sqrt(var), tukey_sigmas);
    s.H.noalias() += w * q.J * q.J.transpose();
    s.g.noalias() -= (w * q.r) * q.J;
  }
  s.used = int(residuals.size());
  return s;
}

// The points (those marked in `usable`) placed by T that land in front of the camera and inside
// `image` one pixel in (for the bilinear sample and its derivatives), in the points' order
// (direct_images.cpp).
std::vector<Landing> landingsInside(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<std::uint8_t>& usable,
                                    const Eigen::Isometry3d& T, const Camera& cam,
                                    const cv::Mat& image);

}  // namespace acvo::direct
