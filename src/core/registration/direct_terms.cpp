// The last-level terms (docs/method.md §6): photometric and point-to-plane residuals of the
// moving cloud's points in the reference's images, with their Gauss-Newton sums.
#include "acvo/registration/direct_terms.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "acvo/math/order_statistics.hpp"

namespace acvo {
namespace {

// Tukey's biweight, (1 - (r / (c sd))^2)^2 and none beyond c standard deviations (c =
// tukey_sigmas; 1 everywhere for c = 0): a residual far outside its term's own scale (a person
// crossing the view, an occlusion) stops pulling.
double tukeyWeight(double r, double sd, double tukey_sigmas) {
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
double planeFade(double scale, double modelled) {
  return modelled > 0.0 ? std::clamp(1.0 - scale / (kPlaneFade * modelled), 0.0, 1.0) : 1.0;
}

bool sameSurface(float a, float b) {
  return a > 0.0f && b > 0.0f && std::abs(a - b) <= kSameSurface * std::min(a, b);
}

// The pixel nearest to coordinate x > -0.5 (std::lround's answer there, halves rounded up): the
// terms round a few projections per point and iteration, and std::lround is a call into libm
// where std::floor is one instruction (SSE4.1, in the build's x86-64-v2).
int nearestPixel(double x) { return int(std::floor(x + 0.5)); }

// Whether the depth around pixel p (its 4 neighbours) is one surface with depth z.
bool smoothAround(const cv::Mat& depth, const cv::Point& p, float z) {
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
constexpr double kMaxBlurCheck = 64.0;  // pixels; a point blurred over more is not used
bool oneSurfaceAlongBlur(const LabelledCloud& cloud, const Eigen::Vector3d& x, const cv::Point& p,
                         float z) {
  if (cloud.blur_motion.matrix() == Eigen::Matrix4d::Identity()) return true;
  const Camera& cam = cloud.camera;
  const Eigen::Vector3d y = cloud.blur_motion * x;
  if (!(y.z() > 0.0)) return false;
  const Eigen::Vector2d m(cam.fx * (y.x() / y.z() - x.x() / x.z()),
                          cam.fy * (y.y() / y.z() - x.y() / x.z()));
  const double length = m.norm();
  if (!(length > 1.0)) return true;  // within the 4-neighbours smoothAround checked
  if (!(length < kMaxBlurCheck)) return false;
  const Eigen::Vector2d dir = m / length;
  const double reach = 0.5 * length + 1.0;
  for (double t = -reach; t <= reach; t += 1.0) {
    const double x_t = p.x + t * dir.x(), y_t = p.y + t * dir.y();
    if (!(x_t > -0.5 && y_t > -0.5)) return false;
    const int u = nearestPixel(x_t), v = nearestPixel(y_t);
    if (u >= cloud.depth.cols || v >= cloud.depth.rows ||
        !sameSurface(cloud.depth.at<float>(v, u), z)) {
      return false;
    }
  }
  return true;
}

// Whether the surface goes on straight from step a to step b (within kFold).
constexpr double kFold = 0.2;  // sine of the largest turn, about 12 deg
bool straight(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
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
GreySample bilinearWithGradient(const cv::Mat& image, double u, double v) {
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
void prefetchAround(const cv::Mat& image, int x, int y, int rows_before, int rows_after) {
  for (int r = -rows_before; r <= rows_after; ++r) {
    const float* row = image.ptr<float>(y + r);
    __builtin_prefetch(row + x - 1);
    __builtin_prefetch(row + x + 2);
  }
}

// The squared distance of pixel (u, v)'s ray from the optical axis, on the plane z = 1: what a
// lens's vignetting depends on (Brightness::at reads the difference between two pixels').
double rho(const Camera& cam, double u, double v) {
  const double x = (u - cam.cx) / cam.fx, y = (v - cam.cy) / cam.fy;
  return x * x + y * y;
}

// An image gradient (gu, gv) at the projection of camera point y, carried to y:
// [gu gv] d pi / d y.
Eigen::Vector3d gradientAtPoint(const Camera& cam, const Eigen::Vector2d& grad,
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

}  // namespace


namespace {

// The kernel cv::GaussianBlur takes for kSmoothing on floats: 8 sigma + 1 taps, made odd.
cv::Mat smoothingKernel(double smoothing) {
  const int taps = int(std::lround(smoothing * 8.0 + 1.0)) | 1;
  return cv::getGaussianKernel(taps, smoothing, CV_32F);
}

// The grey image as the terms sample it: in floats, smoothed by kSmoothing. cv::sepFilter2D
// from the 8-bit image straight to floats gives cv::GaussianBlur's values on the image
// converted to floats (equal to the last bit on teddy200's and kitchen7s_dev's frames) in
// about half the time: the conversion was a pass of its own.
cv::Mat smoothedIntensity(const cv::Mat& gray, double smoothing) {
  const cv::Mat k = smoothingKernel(smoothing);
  cv::Mat out;
  cv::sepFilter2D(gray, out, CV_32F, k, k, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT_101);
  return out;
}

}  // namespace

DirectImages directImages(const LabelledCloud& cloud, bool dense, double depth_noise,
                          bool whole_image, double smoothing, int exact_grid_stride) {
  DirectImages out;
  if (cloud.gray.empty() || cloud.depth.empty() || cloud.pixels.size() != cloud.size()) {
    return out;
  }
  out.depth = cloud.depth;
  out.camera = cloud.camera;
  out.one_surface.resize(cloud.size());
  out.point_intensity.resize(cloud.size());
  // The smoothing of smoothedIntensity (its kernel and reflected border, rows first), at the
  // points' pixels only: the whole image is smoothed only where the reverse photometric term
  // reads it (whole_image) or the frame becomes a reference.
  const cv::Mat kernel = smoothingKernel(smoothing);
  const int taps = kernel.rows, half = taps / 2;
  const float* k = kernel.ptr<float>();
  const cv::Mat& g = cloud.gray;
  auto at = [&](int v, int u) {
    return float(g.at<std::uint8_t>(cv::borderInterpolate(v, g.rows, cv::BORDER_REFLECT_101),
                                     cv::borderInterpolate(u, g.cols, cv::BORDER_REFLECT_101)));
  };
  for (std::size_t j = 0; j < cloud.size(); ++j) {
    const cv::Point& p = cloud.pixels[j];
    const float z = cloud.points[j].z();
    out.one_surface[j] = smoothAround(cloud.depth, p, z) &&
                         oneSurfaceAlongBlur(cloud, cloud.points[j].cast<double>(), p, z);
    const bool inside =
        p.x >= half && p.y >= half && p.x + half < g.cols && p.y + half < g.rows;
    float sum = 0.0f;
    for (int dv = -half; dv <= half; ++dv) {
      float row = 0.0f;
      if (inside) {
        const std::uint8_t* r = g.ptr<std::uint8_t>(p.y + dv) + p.x - half;
        for (int t = 0; t < taps; ++t) row += k[t] * float(r[t]);
      } else {
        for (int du = -half; du <= half; ++du) row += k[du + half] * at(p.y + dv, p.x + du);
      }
      sum += k[dv + half] * row;
    }
    out.point_intensity[j] = sum;
  }
  if (dense && !cloud.depth_of_another_instant) {
    out.grid = denseGrid(cloud.depth, cloud.camera, depth_noise, exact_grid_stride);
  }
  out.smoothing = smoothing;
  if (whole_image) out.intensity = smoothedIntensity(cloud.gray, smoothing);
  return out;
}

DepthGrid denseGrid(const cv::Mat& depth, const Camera& camera, double depth_noise,
                    int exact_grid_stride) {
  DepthGrid grid;
  const cv::Mat& D = depth;
  constexpr int w = kGridWindow, quarter = w * w;
  auto inside = [&D](int u, int v) { return u >= w && v >= w && u + w < D.cols && v + w < D.rows; };
  // The squared twists of the windows that are one surface whole, in units of z^2.
  std::vector<double> t2, T2;
  for (int v = kGridStride / 2; v < D.rows; v += kGridStride) {
    for (int u = kGridStride / 2; u < D.cols; u += kGridStride) {
      const float z = inside(u, v) ? D.at<float>(v, u) : 0.0f;
      if (!(z > 0.0f)) continue;
      // The quarters' sums, the middle row and column left out.
      double q[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
      bool whole = true;
      for (int dv = -w; dv <= w && whole; ++dv) {
        const float* row = D.ptr<float>(v + dv) + u;
        for (int du = -w; du <= w; ++du) {
          if (!sameSurface(row[du], z)) {
            whole = false;
            break;
          }
          if (du != 0 && dv != 0) q[dv > 0][du > 0] += double(row[du]);
        }
      }
      if (!whole) continue;
      const double T = (q[0][0] - q[0][1] - q[1][0] + q[1][1]) / quarter;
      const double t = double(D.at<float>(v, u)) - double(D.at<float>(v, u + 1)) -
                       double(D.at<float>(v + 1, u)) + double(D.at<float>(v + 1, u + 1));
      const double inv_z4 = 1.0 / (double(z) * z * z * z);
      t2.push_back(t * t * inv_z4);
      T2.push_back(T * T * inv_z4);
    }
  }
  if (T2.empty()) return grid;
  // Means of the smallest 80%, not of all: a window across a fold (two walls' corner) twists by
  // its shape. For Gaussian noise that is 0.438 of the variance, for t as for T.
  auto trimmedMean = [](std::vector<double>& x) {
    const auto cut = x.begin() + std::ptrdiff_t(std::max<std::size_t>(1, x.size() * 4 / 5));
    std::nth_element(x.begin(), cut - 1, x.end());
    double sum = 0.0;
    for (auto it = x.begin(); it != cut; ++it) sum += *it;
    return sum / double(cut - x.begin());
  };
  const double mt = trimmedMean(t2), mT = trimmedMean(T2);
  // var(T) = 4 sigma^2 / 9 for noise per pixel: sigma as the windows see it.
  grid.shared_noise = std::sqrt(double(quarter) * mT / 0.438 / 4.0);
  grid.independence = mT > 0.0 ? std::min(1.0, mt / (double(quarter) * mT)) : 0.0;
  const double exact = planeFade(grid.shared_noise, depth_noise);
  grid.weight = std::max(grid.independence >= kMinIndependence ? grid.independence : 0.0, exact);
  if (!(grid.weight > 0.0)) return grid;
  // The twists above read every kGridStride-th pixel whatever the depth; the points are denser
  // where it is exact.
  grid.stride = grid.shared_noise < kExactDepthNoise * depth_noise ? exact_grid_stride : kGridStride;
  const int stride = grid.stride;
  // The window means, over the pixels of the centre's surface.
  grid.points.reserve(std::size_t(D.rows / stride + 1) * std::size_t(D.cols / stride + 1));
  for (int v = stride / 2; v < D.rows; v += stride) {
    for (int u = stride / 2; u < D.cols; u += stride) {
      const float z = D.at<float>(v, u);
      if (!(z > 0.0f) || !smoothAround(D, cv::Point(u, v), z)) continue;
      // Sums of u z, v z and z: the mean point is their back-projection.
      double uz = 0.0, vz = 0.0, sz = 0.0;
      int n = 0;
      for (int vv = std::max(0, v - w); vv <= std::min(D.rows - 1, v + w); ++vv) {
        const float* row = D.ptr<float>(vv);
        double row_uz = 0.0, row_z = 0.0;
        for (int uu = std::max(0, u - w); uu <= std::min(D.cols - 1, u + w); ++uu) {
          if (!sameSurface(row[uu], z)) continue;
          row_uz += double(uu) * row[uu];
          row_z += row[uu];
          ++n;
        }
        uz += row_uz;
        vz += double(vv) * row_z;
        sz += row_z;
      }
      if (2 * n < (2 * w + 1) * (2 * w + 1)) continue;
      grid.points.emplace_back((uz - camera.cx * sz) / (camera.fx * n),
                               (vz - camera.cy * sz) / (camera.fy * n), sz / n);
    }
  }
  return grid;
}

void addReferenceImages(DirectImages& images, const LabelledCloud& cloud) {
  if (images.empty() || images.reference || cloud.gray.empty()) return;
  if (images.intensity.empty()) images.intensity = smoothedIntensity(cloud.gray, images.smoothing);
  images.reference = true;
  if (images.grid.empty()) return;
  const cv::Mat& D = images.depth;
  const Camera& c = images.camera;
  cv::Mat points(D.size(), CV_32FC4, cv::Scalar::all(0.0));
  for (int v = 0; v < D.rows; ++v) {
    const float* d = D.ptr<float>(v);
    auto* out = points.ptr<cv::Vec4f>(v);
    const float y = float((v - c.cy) / c.fy);
    for (int u = 0; u < D.cols; ++u) {
      if (d[u] > 0.0f) out[u] = cv::Vec4f(float((u - c.cx) / c.fx) * d[u], y * d[u], d[u], 1.0f);
    }
  }
  // Each pixel's window sum: a box filter's running sums (floats hold 49 points' sums to a
  // hundredth of a millimetre).
  constexpr int side = 2 * kGridWindow + 1;
  cv::boxFilter(points, images.point_sums, CV_32F, cv::Size(side, side), cv::Point(-1, -1), false,
                cv::BORDER_CONSTANT);
}

namespace {

// The points (those marked in `usable`) placed by T that land in front of the camera and inside
// `image` one pixel in (for the bilinear sample and its derivatives), in the points' order.
std::vector<Landing> landingsInside(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<std::uint8_t>& usable,
                                    const Eigen::Isometry3d& T, const Camera& cam,
                                    const cv::Mat& image) {
  std::vector<Landing> out;
  out.reserve(points.size());
  Landing l;
  for (l.j = 0; l.j < points.size(); ++l.j) {
    if (!usable[l.j]) continue;
    l.y = T * points[l.j].cast<double>();
    if (!(l.y.z() > 0.0)) continue;
    l.u = cam.fx * l.y.x() / l.y.z() + cam.cx;
    l.v = cam.fy * l.y.y() / l.y.z() + cam.cy;
    if (!(l.u >= 1.0 && l.v >= 1.0 && l.u < image.cols - 2.0 && l.v < image.rows - 2.0)) continue;
    out.push_back(l);
  }
  return out;
}

}  // namespace

std::vector<Landing> landings(const DirectImages& reference, const DirectImages& moving_images,
                              const LabelledCloud& moving, const Eigen::Isometry3d& T) {
  if (!reference.isReference() || moving_images.empty() ||
      moving_images.one_surface.size() != moving.size()) {
    return {};
  }
  const cv::Mat& D = reference.depth;
  std::vector<Landing> out =
      landingsInside(moving.points, moving_images.one_surface, T, reference.camera, D);
  // Not occluded: the reference's depth there, read with the pixel kAhead on asked for.
  std::size_t kept = 0;
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (k + kAhead < out.size()) {
      const Landing& next = out[k + kAhead];
      __builtin_prefetch(D.ptr<float>(nearestPixel(next.v)) + nearestPixel(next.u));
    }
    const Landing& here = out[k];
    if (sameSurface(D.at<float>(nearestPixel(here.v), nearestPixel(here.u)), float(here.y.z()))) {
      out[kept++] = here;
    }
  }
  out.resize(kept);
  return out;
}

Brightness brightnessOf(const std::vector<GreyPair>& pairs, bool gain, bool vignetting) {
  struct Usable {
    double log_ratio, shift, flat;
  };
  std::vector<Usable> usable;
  usable.reserve(pairs.size());
  const std::size_t stride =
      std::max<std::size_t>(1, (pairs.size() + kBrightnessPairs - 1) / kBrightnessPairs);
  for (std::size_t k = 0; k < pairs.size(); k += stride) {
    const GreyPair& p = pairs[k];
    if (p.reference < kSaturated && p.moving < kSaturated && p.reference >= kDark &&
        p.moving >= kDark) {
      usable.push_back({std::log(double(p.reference) / double(p.moving)), p.shift, p.flat});
    }
  }
  if (usable.size() < kMinGainPairs || !(gain || vignetting)) return {};
  // The lower median of log(ratio) - v shift (weightedMedian's answer for equal weights).
  std::vector<double> rest(usable.size());
  auto logGain = [&](double v) {
    for (std::size_t k = 0; k < usable.size(); ++k) {
      rest[k] = usable[k].log_ratio - v * usable[k].shift;
    }
    return kthSmallest(rest.data(), rest.data() + rest.size(), (rest.size() - 1) / 2);
  };
  Brightness b;
  double log_gain = gain ? logGain(0.0) : 0.0;
  if (vignetting) {
    std::vector<std::pair<double, double>> slopes;  // (slope, weight)
    slopes.reserve(usable.size());
    for (int round = 0; round < kBrightnessRounds; ++round) {
      slopes.clear();
      for (const Usable& u : usable) {
        if (std::abs(u.shift) > 1e-6) {
          slopes.emplace_back((u.log_ratio - log_gain) / u.shift, std::abs(u.shift) * u.flat);
        }
      }
      if (slopes.size() < kMinGainPairs) break;
      b.vignetting = std::clamp(weightedMedian(slopes), kMinVignetting, kMaxVignetting);
      if (gain) log_gain = logGain(b.vignetting);
    }
  }
  b.gain = std::exp(log_gain);
  if (!(b.gain >= 1.0 / kMaxGain && b.gain <= kMaxGain)) return {};
  return b;
}

DirectSums photometricSums(const DirectImages& reference, const DirectImages& moving_images,
                           const LabelledCloud& moving, const std::vector<Landing>& landed,
                           bool gain, bool vignetting, double edge_position2,
                           double tukey_sigmas) {
  if (!reference.isReference() || moving_images.point_intensity.size() != moving.size()) return {};
  const Camera& cam = reference.camera;
  const bool pixels = moving.pixels.size() == moving.size();
  std::vector<GreyPair> grey(landed.size());
  std::vector<Residual> residuals(landed.size());
  for (std::size_t k = 0; k < landed.size(); ++k) {
    if (k + kAhead < landed.size()) {
      const Landing& next = landed[k + kAhead];
      prefetchAround(reference.intensity, int(next.u), int(next.v), 1, 2);
    }
    const Landing& l = landed[k];
    const GreySample at = bilinearWithGradient(reference.intensity, l.u, l.v);
    const Eigen::Vector2d& grad = at.gradient;
    const double gu = grad.x(), gv = grad.y();
    // d r / d y = [gu gv] d pi / d y; d y / d xi = [-hat(y), I], and (-hat(y))^T d = y x d.
    const Eigen::Vector3d d = gradientAtPoint(cam, grad, l.y);
    Residual& q = residuals[k];
    q.say = gu * gu + gv * gv;
    q.J << l.y.cross(d), d;
    GreyPair& g = grey[k];
    g.reference = at.value;
    g.moving = moving_images.point_intensity[l.j];
    if (pixels) {
      const cv::Point& p = moving.pixels[l.j];
      g.shift = float(rho(cam, l.u, l.v) - rho(cam, p.x, p.y));
    }
    g.flat = float(1.0 / (1.0 + q.say / (kFlatGradient * kFlatGradient)));
  }
  const Brightness b = brightnessOf(grey, gain, vignetting);
  for (std::size_t k = 0; k < landed.size(); ++k) {
    residuals[k].r = double(grey[k].reference) - b.at(grey[k].shift) * double(grey[k].moving);
  }
  DirectSums s = sumsOf(residuals, kMinIntensityScale, edge_position2, tukey_sigmas,
                        [](double) { return 1.0; });
  s.brightness = b;
  return s;
}

DirectSums reversePhotometricSums(const DirectImages& reference,
                                  const LabelledCloud& reference_cloud,
                                  const DirectImages& moving_images,
                                  const LabelledCloud& moving_cloud, const Eigen::Isometry3d& T,
                                  const Brightness& brightness, double edge_position2,
                                  double tukey_sigmas) {
  const cv::Mat& I = moving_images.intensity;
  const std::size_t n = reference_cloud.size();
  if (I.empty() || moving_images.empty() || reference.point_intensity.size() != n ||
      reference.one_surface.size() != n || reference_cloud.pixels.size() != n) {
    return {};
  }
  const Camera& cam = moving_images.camera;
  const cv::Mat& D = moving_images.depth;
  const Eigen::Isometry3d to_moving = T.inverse();
  const Eigen::Matrix3d R = T.linear();
  // Where the reference's points land in the moving image (as Landing: j the reference point),
  // then their samples, each with the rows of the one kAhead on asked for.
  const std::vector<Landing> landed =
      landingsInside(reference_cloud.points, reference.one_surface, to_moving, cam, D);
  std::vector<Residual> residuals;
  residuals.reserve(landed.size());
  for (std::size_t k = 0; k < landed.size(); ++k) {
    if (k + kAhead < landed.size()) {
      const Landing& next = landed[k + kAhead];
      prefetchAround(D, nearestPixel(next.u), nearestPixel(next.v), 1, 1);
      prefetchAround(I, int(next.u), int(next.v), 1, 2);
    }
    const std::size_t i = landed[k].j;
    const Eigen::Vector3d x = reference_cloud.points[i].cast<double>();
    const Eigen::Vector3d& z = landed[k].y;
    const double u = landed[k].u, v = landed[k].v;
    const cv::Point at(nearestPixel(u), nearestPixel(v));
    const float depth = float(z.z());
    if (!sameSurface(D.at<float>(at), depth) || !smoothAround(D, at, depth) ||
        !oneSurfaceAlongBlur(moving_cloud, z, at, depth)) {
      continue;
    }
    const GreySample sample = bilinearWithGradient(I, u, v);
    const Eigen::Vector2d& grad = sample.gradient;
    const double gu = grad.x(), gv = grad.y();
    // The moving image's d I / d z, then with T <- exp(xi) T: z = T^-1 exp(-xi) x, so
    // d z = R^T (x x omega - nu), and with e = R d I / d z: d r = -B (e . (x x omega) - e . nu).
    const Eigen::Vector3d e = R * gradientAtPoint(cam, grad, z);
    const cv::Point& p = reference_cloud.pixels[i];
    const double b = brightness.at(rho(cam, p.x, p.y) - rho(cam, u, v));
    Residual q;
    q.r = double(reference.point_intensity[i]) - b * double(sample.value);
    q.say = b * b * (gu * gu + gv * gv);
    q.J << -b * e.cross(x), b * e;
    residuals.push_back(q);
  }
  return sumsOf(residuals, kMinIntensityScale, edge_position2, tukey_sigmas,
                [](double) { return 1.0; });
}

DirectSums pointToPlaneSums(const DirectImages& reference, const std::vector<Landing>& landed,
                            double depth_noise, PlaneMemo* memo, double tukey_sigmas) {
  if (reference.empty()) return {};
  const Camera& cam = reference.camera;
  const cv::Mat& D = reference.depth;
  auto pointAt = [&](int u, int v) { return cam.backProject(u, v, double(D.at<float>(v, u))); };
  // The reference's plane at pixel (u, v).
  auto planeAt = [&](int u, int v, PlaneMemo::Plane& plane) {
    plane.pixel = v * D.cols + u;
    plane.found = false;
    if (!smoothAround(D, cv::Point(u, v), D.at<float>(v, u))) return;
    plane.x = pointAt(u, v);
    const Eigen::Vector3d left = plane.x - pointAt(u - 1, v), right = pointAt(u + 1, v) - plane.x;
    const Eigen::Vector3d up = plane.x - pointAt(u, v - 1), down = pointAt(u, v + 1) - plane.x;
    // A plane only: a fold (a corner of two walls, a box's edge) has no normal.
    if (!straight(left, right) || !straight(up, down)) return;
    plane.n = (left + right).cross(up + down).normalized();
    plane.found = plane.n.allFinite();
  };
  std::vector<Residual> residuals;
  residuals.reserve(landed.size());
  PlaneMemo::Plane here;
  for (std::size_t k = 0; k < landed.size(); ++k) {
    if (k + kAhead < landed.size()) {
      const Landing& next = landed[k + kAhead];
      prefetchAround(D, nearestPixel(next.u), nearestPixel(next.v), 1, 1);
    }
    const Landing& l = landed[k];
    const int u = nearestPixel(l.u), v = nearestPixel(l.v);
    PlaneMemo::Plane& plane = memo ? memo->of(l.j) : here;
    if (plane.pixel != v * D.cols + u) planeAt(u, v, plane);
    if (!plane.found) continue;
    const Eigen::Vector3d& x = plane.x;
    const Eigen::Vector3d& n = plane.n;
    // Depth noise grows with z^2: residuals in metres per metre^2 share one scale.
    const double inv_z2 = 1.0 / (l.y.z() * l.y.z());
    Residual q{n.dot(l.y - x) * inv_z2, Vector6d(), 1.0};
    q.J << inv_z2 * l.y.cross(n), inv_z2 * n;
    residuals.push_back(q);
  }
  // Both points' depth noise, as the kernel assumes it.
  const double modelled = std::sqrt(2.0) * depth_noise;
  return sumsOf(residuals, kMinPlaneScale, 0.0, tukey_sigmas,
                [modelled](double scale) { return planeFade(scale, modelled); });
}

namespace {

// The mean point of the window around (u, v) from the window sums of (x, y, z, 1), and how
// many points it holds (in count).
Eigen::Vector3d windowMean(const cv::Mat& sums, int u, int v, double& count) {
  const cv::Vec4f& s = sums.at<cv::Vec4f>(v, u);
  count = double(s[3]);
  if (!(count > 0.0)) return Eigen::Vector3d::Zero();
  return Eigen::Vector3d(double(s[0]), double(s[1]), double(s[2])) / count;
}

}  // namespace

double denseWeight(const DirectImages& reference, const DirectImages& moving_images) {
  const bool both = !reference.point_sums.empty() && !moving_images.grid.empty();
  return both ? moving_images.grid.weight : 0.0;
}

DirectSums densePlaneSums(const DirectImages& reference, const DirectImages& moving_images,
                          const Eigen::Isometry3d& T, double tukey_sigmas) {
  const double weight = denseWeight(reference, moving_images);
  if (!(weight > 0.0)) return {};
  const DepthGrid& grid = moving_images.grid;
  const Camera& cam = reference.camera;
  const cv::Mat& D = reference.depth;
  const cv::Mat& S = reference.point_sums;
  constexpr int w = kGridWindow, r = kNormalReach, margin = kGridWindow + kNormalReach + 1;
  constexpr double half = 0.5 * (2 * w + 1) * (2 * w + 1);
  // Where the grid's points land, then their planes, each with the pixels of the one kAhead on
  // asked for (the window sums are 16 bytes a pixel: 4.9 MB at 640x480).
  struct GridLanding {
    Eigen::Vector3d y;
    int u, v;
  };
  std::vector<GridLanding> landed;
  landed.reserve(grid.points.size());
  for (const Eigen::Vector3d& p : grid.points) {
    const Eigen::Vector3d y = T * p;
    if (!(y.z() > 0.0)) continue;
    const int u = int(std::lround(cam.fx * y.x() / y.z() + cam.cx));
    const int v = int(std::lround(cam.fy * y.y() / y.z() + cam.cy));
    if (u < margin || v < margin || u + margin >= D.cols || v + margin >= D.rows) continue;
    landed.push_back({y, u, v});
  }
  std::vector<Residual> residuals;
  residuals.reserve(landed.size());
  for (std::size_t k = 0; k < landed.size(); ++k) {
    if (k + kAhead < landed.size()) {
      const GridLanding& next = landed[k + kAhead];
      for (const cv::Point d : {cv::Point(0, 0), cv::Point(-r, 0), cv::Point(r, 0),
                                cv::Point(0, -r), cv::Point(0, r)}) {
        __builtin_prefetch(&D.at<float>(next.v + d.y, next.u + d.x));
        __builtin_prefetch(&S.at<cv::Vec4f>(next.v + d.y, next.u + d.x));
      }
    }
    const Eigen::Vector3d& y = landed[k].y;
    const int u = landed[k].u, v = landed[k].v;
    const float z = D.at<float>(v, u);
    // Not occluded; the pixels the plane is taken from all on the same surface.
    if (!sameSurface(z, float(y.z())) || !sameSurface(D.at<float>(v, u - r), z) ||
        !sameSurface(D.at<float>(v, u + r), z) || !sameSurface(D.at<float>(v - r, u), z) ||
        !sameSurface(D.at<float>(v + r, u), z)) {
      continue;
    }
    double n0 = 0.0, n1 = 0.0, n2 = 0.0, n3 = 0.0, n4 = 0.0;
    const Eigen::Vector3d x = windowMean(S, u, v, n0);
    const Eigen::Vector3d left = x - windowMean(S, u - r, v, n1);
    const Eigen::Vector3d right = windowMean(S, u + r, v, n2) - x;
    const Eigen::Vector3d up = x - windowMean(S, u, v - r, n3);
    const Eigen::Vector3d down = windowMean(S, u, v + r, n4) - x;
    if (std::min({n0, n1, n2, n3, n4}) < half || !sameSurface(float(x.z()), z)) continue;
    if (!straight(left, right) || !straight(up, down)) continue;
    const Eigen::Vector3d n = (left + right).cross(up + down).normalized();
    if (!n.allFinite()) continue;
    const double inv_z2 = 1.0 / (y.z() * y.z());
    Residual q{n.dot(y - x) * inv_z2, Vector6d(), 1.0};
    q.J << inv_z2 * y.cross(n), inv_z2 * n;
    residuals.push_back(q);
  }
  return sumsOf(residuals, kMinPlaneScale, 0.0, tukey_sigmas, [weight](double) { return weight; });
}

}  // namespace acvo
