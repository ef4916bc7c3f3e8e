#include "synthetic_room.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace acvo_test {
namespace {

// The room: an axis-aligned box seen from inside, plus boxes seen from outside.
struct Box {
  Eigen::Vector3d lo, hi;
};
const Box kRoom{{-2.0, -1.2, -1.0}, {2.0, 1.3, 4.0}};  // world y points down, like the camera
const std::array<Box, 2> kObjects{{
    {{-1.0, 0.5, 2.2}, {-0.2, 1.3, 3.0}},
    {{0.6, 0.8, 1.6}, {1.2, 1.3, 2.2}},
}};

struct Hit {
  double t = std::numeric_limits<double>::infinity();
  Eigen::Vector3d point;
  int axis = 0;  // the axis the hit face is normal to
  int id = 0;    // which surface, for the texture seed
};

std::uint32_t hash(std::int64_t a, std::int64_t b, std::int64_t c) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::int64_t v : {a, b, c}) {
    h ^= static_cast<std::uint64_t>(v) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h *= 1099511628211ull;
  }
  return static_cast<std::uint32_t>(h ^ (h >> 29));
}

// Tiles of 0.25 m with random saturated colours and brightness, so that both the colour
// labels and the gradients carry information.
cv::Vec3d texture(const Hit& hit) {
  const int u_axis = (hit.axis + 1) % 3, v_axis = (hit.axis + 2) % 3;
  const double tile = 0.25;
  const auto iu = static_cast<std::int64_t>(std::floor(hit.point[u_axis] / tile));
  const auto iv = static_cast<std::int64_t>(std::floor(hit.point[v_axis] / tile));
  const std::uint32_t h = hash(iu, iv, hit.id);
  const double hue = (h & 0xff) / 255.0 * 6.0;
  const double value = 70.0 + ((h >> 8) & 0x7f) * 1.4;
  const double sat = 0.35 + ((h >> 16) & 0x3f) / 63.0 * 0.6;
  // HSV -> RGB.
  const double c = value * sat, x = c * (1.0 - std::abs(std::fmod(hue, 2.0) - 1.0));
  cv::Vec3d rgb;
  switch (static_cast<int>(hue) % 6) {
    case 0: rgb = {c, x, 0}; break;
    case 1: rgb = {x, c, 0}; break;
    case 2: rgb = {0, c, x}; break;
    case 3: rgb = {0, x, c}; break;
    case 4: rgb = {x, 0, c}; break;
    default: rgb = {c, 0, x}; break;
  }
  return rgb + cv::Vec3d::all(value - c);
}

// Ray against the inside of the room: the nearest exit face.
void hitRoom(const Eigen::Vector3d& o, const Eigen::Vector3d& d, Hit& best) {
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) continue;
    const double bound = d[a] > 0 ? kRoom.hi[a] : kRoom.lo[a];
    const double t = (bound - o[a]) / d[a];
    if (t > 0 && t < best.t) {
      best.t = t;
      best.axis = a;
      best.id = 2 * a + (d[a] > 0 ? 1 : 0);
    }
  }
}

// Slab test against a box seen from outside.
void hitBox(const Box& box, int id, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
            Hit& best) {
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  int axis = 0;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < box.lo[a] || o[a] > box.hi[a]) return;
      continue;
    }
    double t0 = (box.lo[a] - o[a]) / d[a], t1 = (box.hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) {
      t_near = t0;
      axis = a;
    }
    t_far = std::min(t_far, t1);
  }
  if (t_near > 0 && t_near <= t_far && t_near < best.t) {
    best.t = t_near;
    best.axis = axis;
    best.id = 10 + id;
  }
}

Hit castRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  Hit hit;
  hitRoom(o, d, hit);
  for (std::size_t i = 0; i < kObjects.size(); ++i) hitBox(kObjects[i], static_cast<int>(i), o, d, hit);
  hit.point = o + hit.t * d;
  return hit;
}

Eigen::Isometry3d expSe3(const Eigen::Vector3d& omega, const Eigen::Vector3d& v) {
  // Small motions only: rotation from the axis-angle, translation taken as is.
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  if (omega.norm() > 0) t.linear() = Eigen::AngleAxisd(omega.norm(), omega.normalized()).matrix();
  t.translation() = v;
  return t;
}

}  // namespace

acvo::Camera testCamera() {
  acvo::Camera c;
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = 260.0;
  c.cx = 159.5;
  c.cy = 119.5;
  c.depth_scale = 1.0;
  return c;
}

RgbdImage renderRoom(const Eigen::Isometry3d& world_from_camera, const acvo::Camera& camera) {
  RgbdImage out;
  out.rgb.create(camera.height, camera.width, CV_8UC3);
  out.depth.create(camera.height, camera.width, CV_32FC1);
  const Eigen::Vector3d origin = world_from_camera.translation();
  const Eigen::Matrix3d rot = world_from_camera.rotation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      cv::Vec3d sum(0, 0, 0);
      for (int s = 0; s < 4; ++s) {
        const double du = (s % 2) * 0.5 - 0.25, dv = (s / 2) * 0.5 - 0.25;
        const Eigen::Vector3d ray = rot * camera.backProject(u + du, v + dv, 1.0);
        sum += texture(castRay(origin, ray));
      }
      const Eigen::Vector3d ray_cam = camera.backProject(u, v, 1.0);
      const Hit centre = castRay(origin, rot * ray_cam);
      // The ray has z = 1 in the camera frame, so t is the depth along the optical axis.
      out.depth.at<float>(v, u) = std::isfinite(centre.t) ? static_cast<float>(centre.t) : 0.0f;
      auto& px = out.rgb.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) px[c] = cv::saturate_cast<std::uint8_t>(sum[c] / 4.0);
    }
  }
  return out;
}

Eigen::Isometry3d frameMotion() {
  const double deg = M_PI / 180.0;
  return expSe3(Eigen::Vector3d(0.2, 0.6, 0.1) * deg, Eigen::Vector3d(0.010, -0.004, 0.011));
}

Eigen::Isometry3d cameraPose(int k) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int i = 0; i < k; ++i) pose = pose * frameMotion();
  return pose;
}

Eigen::Isometry3d worldFromFirstCamera() {
  return expSe3(Eigen::Vector3d(-0.05, 0.25, 0.0), Eigen::Vector3d(-0.4, -0.1, 0.2));
}

}  // namespace acvo_test
