// The photometric terms (docs/method.md §6): the moving points' grey values against the
// reference's where they land, and the reference's points' against the moving image.
#include <cstddef>
#include <vector>

#include "direct_helpers.hpp"

namespace acvo {

using direct::bilinearWithGradient;
using direct::GreySample;
using direct::gradientAtPoint;
using direct::kAhead;
using direct::kMinIntensityScale;
using direct::landingsInside;
using direct::nearestPixel;
using direct::oneSurfaceAlongBlur;
using direct::prefetchAround;
using direct::Residual;
using direct::rho;
using direct::sameSurface;
using direct::smoothAround;
using direct::sumsOf;

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

}  // namespace acvo
