// The motion-blur check of the last-level terms: a point's grey value is used only where the
// depth along its blur is its own surface.
#include <cmath>

#include "direct_helpers.hpp"

namespace acvo::direct {

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

}  // namespace acvo::direct
