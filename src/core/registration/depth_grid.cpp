// The depth grid of the dense point-to-plane term (docs/method.md §6): window means of a frame's
// depth on a grid of pixels, and how much of the depth's noise they average away.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "direct_helpers.hpp"

namespace acvo {

using direct::planeFade;
using direct::sameSurface;
using direct::smoothAround;

namespace {

constexpr int w = kGridWindow;       // a window's half size
constexpr int quarter = w * w;  // pixels in a quarter of a window

// The squared twists of the windows that are one surface whole, in units of z^2: t of single
// pixels, T of the four quarter means (DepthGrid), on every kGridStride-th pixel.
struct Twists {
  std::vector<double> t2, T2;
};
Twists twistsOf(const cv::Mat& D) {
  auto inside = [&D](int u, int v) { return u >= w && v >= w && u + w < D.cols && v + w < D.rows; };
  Twists out;
  std::vector<double>& t2 = out.t2;
  std::vector<double>& T2 = out.T2;
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
  return out;
}

// The mean of the smallest 80%, not of all: a window across a fold (two walls' corner) twists by
// its shape. For Gaussian noise that is 0.438 of the variance, for t as for T. Reorders x.
double trimmedMean(std::vector<double>& x) {
  const auto cut = x.begin() + std::ptrdiff_t(std::max<std::size_t>(1, x.size() * 4 / 5));
  std::nth_element(x.begin(), cut - 1, x.end());
  double sum = 0.0;
  for (auto it = x.begin(); it != cut; ++it) sum += *it;
  return sum / double(cut - x.begin());
}

// The window means on every stride-th pixel, over the pixels of the centre's surface (at least
// half the window).
void addWindowMeans(const cv::Mat& D, const Camera& camera, int stride,
                    std::vector<Eigen::Vector3d>& points) {
  points.reserve(std::size_t(D.rows / stride + 1) * std::size_t(D.cols / stride + 1));
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
      points.emplace_back((uz - camera.cx * sz) / (camera.fx * n),
                          (vz - camera.cy * sz) / (camera.fy * n), sz / n);
    }
  }
}

}  // namespace

DepthGrid denseGrid(const cv::Mat& depth, const Camera& camera, double depth_noise,
                    int exact_grid_stride) {
  DepthGrid grid;
  Twists twists = twistsOf(depth);
  if (twists.T2.empty()) return grid;
  const double mt = trimmedMean(twists.t2), mT = trimmedMean(twists.T2);
  // var(T) = 4 sigma^2 / 9 for noise per pixel: sigma as the windows see it.
  grid.shared_noise = std::sqrt(double(quarter) * mT / 0.438 / 4.0);
  grid.independence = mT > 0.0 ? std::min(1.0, mt / (double(quarter) * mT)) : 0.0;
  const double exact = planeFade(grid.shared_noise, depth_noise);
  grid.weight = std::max(grid.independence >= kMinIndependence ? grid.independence : 0.0, exact);
  if (!(grid.weight > 0.0)) return grid;
  // The twists above read every kGridStride-th pixel whatever the depth; the points are denser
  // where it is exact.
  grid.stride = grid.shared_noise < kExactDepthNoise * depth_noise ? exact_grid_stride : kGridStride;
  addWindowMeans(depth, camera, grid.stride, grid.points);
  return grid;
}

}  // namespace acvo
