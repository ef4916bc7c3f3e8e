// Ray casting against quads and oriented boxes.
#include "synth/scene.hpp"

#include <cmath>
#include <limits>

namespace acvo::synth {
namespace {

// Hits closer than this are ignored (a ray starting on a surface must not see it), and
// rectangle bounds are widened by it so that rays through a shared edge (room corners) find
// one of the two surfaces rather than slipping between them.
constexpr double kEpsilon = 1e-9;

// Brightness of box faces -x, +x, -y, +y, -z, +z: a fixed fake light so faces differ.
constexpr double kFaceBrightness[6] = {0.78, 0.9, 0.84, 0.7, 0.64, 1.0};

}  // namespace

RayCaster::RayCaster(const Scene& scene, const Eigen::Vector3d& origin)
    : scene_(&scene), origin_(origin) {
  for (const Quad& q : scene.quads) {
    const Eigen::Vector3d n = q.normal();
    const Eigen::Vector3d r = origin - q.centre;
    quads_.push_back({n, -n.dot(r), q.axis_s, q.axis_t, r.dot(q.axis_s), r.dot(q.axis_t),
                      q.half_s + kEpsilon, q.half_t + kEpsilon});
  }
  for (const Box& b : scene.boxes) {
    const Eigen::Matrix3d world_to_box = b.box_to_world.linear().transpose();
    boxes_.push_back(
        {world_to_box, world_to_box * (origin - b.box_to_world.translation()), b.half_size});
  }
}

bool RayCaster::castQuad(int index, const Eigen::Vector3d& d, double* t_best, Hit* hit) const {
  const PreparedQuad& q = quads_[index];
  const double denom = q.normal.dot(d);
  if (std::abs(denom) < 1e-15) return false;  // parallel to the plane
  const double t = q.numerator / denom;
  if (!(t > kEpsilon && t < *t_best)) return false;
  const double s = q.s0 + t * d.dot(q.axis_s);
  const double u = q.t0 + t * d.dot(q.axis_t);
  if (std::abs(s) > q.half_s || std::abs(u) > q.half_t) return false;
  *t_best = t;
  hit->t = t;
  hit->normal = denom > 0 ? Eigen::Vector3d(-q.normal) : q.normal;
  hit->uv = {s, u};
  hit->surface = index;
  hit->material = scene_->quads[index].material;
  hit->brightness = 1.0;
  return true;
}

// Slab test in the box's own frame.
bool RayCaster::castBox(int index, const Eigen::Vector3d& direction, double* t_best,
                        Hit* hit) const {
  const PreparedBox& b = boxes_[index];
  const Eigen::Vector3d d = b.world_to_box * direction;
  const Eigen::Vector3d& o = b.origin;
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  int near_axis = -1;
  for (int i = 0; i < 3; ++i) {
    const double h = b.half_size[i];
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(o[i]) > h) return false;  // parallel to this slab and outside it
      continue;
    }
    const double inv = 1.0 / d[i];
    double t0 = (-h - o[i]) * inv, t1 = (h - o[i]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) t_near = t0, near_axis = i;
    if (t1 < t_far) t_far = t1;
    if (t_near > t_far) return false;
  }
  // Only entering hits: a camera never sits inside a box.
  if (near_axis < 0 || !(t_near > kEpsilon && t_near < *t_best)) return false;
  const int a = near_axis, b1 = (a + 1) % 3, b2 = (a + 2) % 3;
  const bool positive_face = d[a] < 0;  // the ray enters through the face it travels against
  const int face = 2 * a + (positive_face ? 1 : 0);
  const Eigen::Vector3d local = o + t_near * d;
  *t_best = t_near;
  hit->t = t_near;
  hit->normal = b.world_to_box.row(a).transpose() * (positive_face ? 1.0 : -1.0);
  // Faces get texture coordinates offset from each other so they do not look alike.
  hit->uv = {local[b1] + 3.7 * face, local[b2]};
  hit->surface = static_cast<int>(quads_.size()) + 6 * index + face;
  hit->material = scene_->boxes[index].material;
  hit->brightness = kFaceBrightness[face];
  return true;
}

bool RayCaster::cast(const Eigen::Vector3d& direction, Hit* hit, const int* candidates,
                     int candidate_count) const {
  double t_best = std::numeric_limits<double>::infinity();
  const int quad_count = static_cast<int>(quads_.size());
  const int count = candidates ? candidate_count : primitiveCount();
  for (int k = 0; k < count; ++k) {
    const int p = candidates ? candidates[k] : k;
    if (p < quad_count)
      castQuad(p, direction, &t_best, hit);
    else
      castBox(p - quad_count, direction, &t_best, hit);
  }
  if (!std::isfinite(t_best)) return false;
  hit->point = origin_ + t_best * direction;
  return true;
}

bool intersect(const Scene& scene, const Ray& ray, Hit* hit) {
  return RayCaster(scene, ray.origin).cast(ray.direction, hit);
}

}  // namespace acvo::synth
