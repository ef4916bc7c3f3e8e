#include "synth/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace acvo::synth {
namespace {

void checkCamera(const Camera& camera) {
  if (!camera.valid()) throw std::invalid_argument("synthetic rendering: invalid camera");
}

// Surface metres covered by one pixel at the hit: distance over focal length, stretched by
// the obliquity (capped, so grazing surfaces still keep their coarse texture).
double pixelFootprint(const Hit& hit, const Eigen::Vector3d& direction, double focal) {
  const double length = direction.norm();
  const double cosine = std::abs(hit.normal.dot(direction)) / length;
  return hit.t * length / (focal * std::max(cosine, 0.1));
}

// Degrades the exact depth and the (possibly blurred) colour when asked, and packs the frame.
SynthFrame finish(const Eigen::Isometry3d& pose, const RenderOptions& options, std::uint64_t seed,
                  const RayCast& exact, cv::Mat colour) {
  SynthFrame frame;
  frame.pose = pose;
  frame.camera = options.camera;
  frame.surface = exact.surface;
  if (options.brightness != 1.0) colour *= options.brightness;
  if (options.vignetting != 0.0) {
    const Camera c = options.colourCamera();
    for (int v = 0; v < colour.rows; ++v) {
      auto* row = colour.ptr<cv::Vec3f>(v);
      const double y = (v - c.cy) / c.fy;
      for (int u = 0; u < colour.cols; ++u) {
        const double x = (u - c.cx) / c.fx;
        row[u] *= static_cast<float>(std::exp(options.vignetting * (x * x + y * y)));
      }
    }
  }
  if (options.noise) {
    frame.depth_m = degradeDepth(exact.depth, options.kinect, options.camera.depth_scale, seed);
    addColourNoise(colour, options.kinect.colour_sigma, seed);
  } else {
    frame.depth_m = exact.depth;
  }
  colour.convertTo(frame.bgr, CV_8UC3);  // rounds to nearest and saturates
  return frame;
}

// Pixels that may see a primitive (inclusive ranges; empty when u0 > u1).
struct PixelRect {
  int u0, u1, v0, v1;
};

// The image rectangle around the projected corners, one pixel wider for rounding. A convex
// primitive entirely in front of the camera projects inside its corners' convex hull; one
// reaching behind the camera (or unbounded) may cover any pixel.
PixelRect cornerBounds(const std::vector<Eigen::Vector3d>& corners, const Camera& camera,
                       const Eigen::Isometry3d& world_to_camera) {
  const PixelRect everything{0, camera.width - 1, 0, camera.height - 1};
  double u_min = std::numeric_limits<double>::infinity(), v_min = u_min;
  double u_max = -u_min, v_max = -u_min;
  for (const Eigen::Vector3d& corner : corners) {
    if (!corner.allFinite()) return everything;
    const Eigen::Vector3d p = world_to_camera * corner;
    if (p.z() < 1e-6) return everything;
    const Eigen::Vector2d px = camera.project(p);
    u_min = std::min(u_min, px.x()), u_max = std::max(u_max, px.x());
    v_min = std::min(v_min, px.y()), v_max = std::max(v_max, px.y());
  }
  auto clampTo = [](double x, int hi) {
    return static_cast<int>(std::clamp(x, -1.0, static_cast<double>(hi) + 1.0));
  };
  return {std::max(0, clampTo(std::floor(u_min) - 1, camera.width)),
          std::min(camera.width - 1, clampTo(std::ceil(u_max) + 1, camera.width)),
          std::max(0, clampTo(std::floor(v_min) - 1, camera.height)),
          std::min(camera.height - 1, clampTo(std::ceil(v_max) + 1, camera.height))};
}

// Per primitive (RayCaster's numbering), the pixels whose rays may hit it: with a few boxes
// on screen at a time, most rays test only the room and one or two boxes.
std::vector<PixelRect> primitiveBounds(const Scene& scene, const Camera& camera,
                                       const Eigen::Isometry3d& pose) {
  const Eigen::Isometry3d world_to_camera = pose.inverse();
  std::vector<PixelRect> bounds;
  std::vector<Eigen::Vector3d> corners;
  for (const Quad& q : scene.quads) {
    corners.clear();
    for (double a : {-1.0, 1.0})
      for (double b : {-1.0, 1.0})
        corners.push_back(q.centre + a * q.half_s * q.axis_s + b * q.half_t * q.axis_t);
    bounds.push_back(cornerBounds(corners, camera, world_to_camera));
  }
  for (const Box& box : scene.boxes) {
    corners.clear();
    for (double a : {-1.0, 1.0})
      for (double b : {-1.0, 1.0})
        for (double c : {-1.0, 1.0})
          corners.push_back(box.box_to_world *
                            Eigen::Vector3d(a, b, c).cwiseProduct(box.half_size));
    bounds.push_back(cornerBounds(corners, camera, world_to_camera));
  }
  return bounds;
}

// The colour seen from the colour camera at the depth camera's `pose` (the exact colour of
// `exact` when the two are one camera).
cv::Mat colourAt(const Scene& scene, const Eigen::Isometry3d& pose, const RenderOptions& options,
                 const RayCast* exact) {
  if (options.colourRegistered()) {
    return exact ? exact->colour : rayCast(scene, options.camera, pose).colour;
  }
  return rayCast(scene, options.colourCamera(), options.colourPose(pose)).colour;
}

}  // namespace

Camera RenderOptions::colourCamera() const {
  Camera c = camera;
  c.fx *= colour_focal_ratio;
  c.fy *= colour_focal_ratio;
  return c;
}

Eigen::Isometry3d RenderOptions::colourPose(const Eigen::Isometry3d& pose) const {
  return pose * Eigen::Translation3d(colour_baseline, 0.0, 0.0);
}

Frame SynthFrame::toFrame() const {
  Frame f;
  f.color = bgr;
  f.order = ColorOrder::kBgr;
  f.depth = depth_m;
  f.camera = camera;
  f.stamp = stamp;
  f.depth_stamp = depth_stamp;
  return f;
}

RayCast rayCast(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& pose) {
  checkCamera(camera);
  RayCast out;
  out.colour.create(camera.height, camera.width, CV_32FC3);
  out.depth.create(camera.height, camera.width, CV_32FC1);
  out.surface.create(camera.height, camera.width, CV_32SC1);
  const RayCaster caster(scene, pose.translation());
  const std::vector<PixelRect> bounds = primitiveBounds(scene, camera, pose);
  const Eigen::Matrix3d R = pose.linear();
  const double focal = std::sqrt(std::abs(camera.fx * camera.fy));  // (negative: a mirrored axis)
  tbb::parallel_for(tbb::blocked_range<int>(0, camera.height),
                    [&](const tbb::blocked_range<int>& r) {
                      std::vector<int> in_row, candidates(bounds.size());
                      for (int v = r.begin(); v < r.end(); ++v) {
                        in_row.clear();
                        for (int p = 0; p < static_cast<int>(bounds.size()); ++p)
                          if (bounds[p].v0 <= v && v <= bounds[p].v1) in_row.push_back(p);
                        auto* colour = out.colour.ptr<cv::Vec3f>(v);
                        auto* depth = out.depth.ptr<float>(v);
                        auto* surface = out.surface.ptr<int>(v);
                        const double y = (v - camera.cy) / camera.fy;
                        for (int u = 0; u < camera.width; ++u) {
                          int count = 0;
                          for (int p : in_row)
                            if (bounds[p].u0 <= u && u <= bounds[p].u1) candidates[count++] = p;
                          // Camera-frame direction with unit z: the hit's t is its depth.
                          const Eigen::Vector3d direction =
                              R * Eigen::Vector3d((u - camera.cx) / camera.fx, y, 1.0);
                          Hit hit;
                          if (!caster.cast(direction, &hit, candidates.data(), count)) {
                            colour[u] = cv::Vec3f(0, 0, 0);
                            depth[u] = 0.0f;
                            surface[u] = -1;
                            continue;
                          }
                          const Eigen::Vector3d c =
                              surfaceColour(scene.materials[hit.material], hit.uv.x(), hit.uv.y(),
                                            pixelFootprint(hit, direction, focal), hit.brightness);
                          colour[u] = cv::Vec3f(c.x(), c.y(), c.z());
                          depth[u] = static_cast<float>(hit.t);
                          surface[u] = hit.surface;
                        }
                      }
                    });
  return out;
}

SynthFrame render(const Scene& scene, const Eigen::Isometry3d& pose, const RenderOptions& options,
                  std::uint64_t seed) {
  const RayCast exact = rayCast(scene, options.camera, pose);
  return finish(pose, options, seed, exact, colourAt(scene, pose, options, &exact));
}

SynthFrame renderBlurred(const Scene& scene, const Eigen::Isometry3d& pose,
                         const std::vector<Eigen::Isometry3d>& exposure,
                         const RenderOptions& options, std::uint64_t seed) {
  if (exposure.empty()) return render(scene, pose, options, seed);
  const RayCast exact = rayCast(scene, options.camera, pose);
  cv::Mat sum(exact.colour.size(), CV_32FC3, cv::Scalar::all(0));
  for (const Eigen::Isometry3d& sub_pose : exposure) {
    // The middle of an odd number of sub-frames is usually the frame's own pose.
    const bool same = sub_pose.matrix() == pose.matrix();
    sum += colourAt(scene, sub_pose, options, same ? &exact : nullptr);
  }
  cv::Mat colour = sum / static_cast<double>(exposure.size());
  return finish(pose, options, seed, exact, colour);
}

}  // namespace acvo::synth
