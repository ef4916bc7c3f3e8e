// The point-to-plane terms (docs/method.md §6): each landed point against the plane of the
// reference's depth where it lands, and the moving depth grid's window means against the
// reference's window means.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "direct_helpers.hpp"

namespace acvo {

using direct::kAhead;
using direct::kMinPlaneScale;
using direct::nearestPixel;
using direct::planeFade;
using direct::prefetchAround;
using direct::Residual;
using direct::sameSurface;
using direct::smoothAround;
using direct::straight;
using direct::sumsOf;

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

// Where a point of the moving depth grid lands in the reference: y there, and its pixel.
struct GridLanding {
  Eigen::Vector3d y;
  int u, v;
};
// The grid's points placed by T that land in front of the camera and `margin` pixels inside the
// reference's depth D, in the grid's order.
std::vector<GridLanding> gridLandings(const DepthGrid& grid, const Eigen::Isometry3d& T,
                                      const Camera& cam, const cv::Mat& D, int margin) {
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
  return landed;
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
  const std::vector<GridLanding> landed = gridLandings(grid, T, cam, D, margin);
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
