// What the last-level terms read of a cloud (docs/method.md §6): its points' smoothed grey
// values and whether each is one surface, a reference's whole smoothed grey image and window
// sums, and where a moving cloud's points land in a reference.
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "direct_helpers.hpp"

namespace acvo {

using direct::kAhead;
using direct::landingsInside;
using direct::nearestPixel;
using direct::oneSurfaceAlongBlur;
using direct::sameSurface;
using direct::smoothAround;

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

// The points (those marked in `usable`) placed by T that land in front of the camera and inside
// `image` one pixel in (for the bilinear sample and its derivatives), in the points' order.
std::vector<Landing> direct::landingsInside(const std::vector<Eigen::Vector3f>& points,
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

}  // namespace acvo
