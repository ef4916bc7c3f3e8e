// The synthetic world: a handful of planar primitives with procedural materials, and the
// ray cast that finds what a pixel sees.
//
// Two kinds of primitive suffice for an indoor room: rectangles (Quad, possibly unbounded)
// and oriented boxes (Box). The ray cast tests every primitive (no acceleration structure:
// scenes hold about twenty), so the nearest hit is exact to double rounding.
//
// Surface ids: quad q is surface q; face f (0..5 = -x, +x, -y, +y, -z, +z of the box's own
// frame) of box b is surface quads.size() + 6 b + f. The renderer can output them per pixel,
// which lets tests tell surface boundaries from texture.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "synth/texture.hpp"

namespace acvo::synth {

// A rectangle centred at `centre` spanning +-half_s along axis_s and +-half_t along axis_t
// (unit, orthogonal); the half sizes may be infinite (an unbounded plane). The normal is
// axis_s x axis_t; both sides are visible. Texture coordinates are (r.axis_s, r.axis_t) for
// r = point - centre.
struct Quad {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_s = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_t = Eigen::Vector3d::UnitY();
  double half_s = 0.5;
  double half_t = 0.5;
  int material = 0;

  Eigen::Vector3d normal() const { return axis_s.cross(axis_t); }
};

// A solid box: the points p with |(box_to_world^-1 p)_i| <= half_size_i. Seen from outside.
struct Box {
  Eigen::Isometry3d box_to_world = Eigen::Isometry3d::Identity();
  Eigen::Vector3d half_size{0.5, 0.5, 0.5};
  int material = 0;
};

// A ray o + t d. `direction` need not be unit length: t is measured in its units, so with
// d = R (x_n, y_n, 1) (a pixel's normalised ray rotated to the world) t is the pixel's depth.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

struct Hit {
  double t = 0.0;                                     // ray parameter of the hit
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    // world
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, facing the ray's origin
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();       // texture coordinates, metres
  int surface = -1;                                   // see the surface ids above
  int material = 0;
  double brightness = 1.0;  // per box face, so that faces of one box differ
};

struct SceneOptions {
  // true: a furnished room (floor, four walls, ceiling, boxes, panels); false: one
  // unbounded plane that fills every view of the trajectories (layout.hpp).
  bool structure = true;
  // true: multi-scale noise with checker / stripe overlays; false: one flat colour per
  // surface (with structure off: a uniform image, nothing to track).
  bool texture = true;
  std::uint64_t seed = 1;  // geometry and materials; same seed -> same scene
  // true: one more material, the last, for a person walking through the room (walkerAt);
  // the scene's own geometry and materials are those of walker off.
  bool walker = false;
};

struct Scene {
  std::vector<Quad> quads;
  std::vector<Box> boxes;
  std::vector<Material> materials;

  int surfaceCount() const { return static_cast<int>(quads.size() + 6 * boxes.size()); }
};

// Builds the scene for `options`, deterministically. Geometry and colours come from separate
// random streams, so structure on/off and texture on/off of one seed share what they can
// (e.g. texture off keeps the exact geometry of texture on).
Scene makeScene(const SceneOptions& options);

// A person walking back and forth across the room in front of the furniture, the scene's one
// moving object (TUM's fr3/walking sequences hold two): a box of a person's size (0.5 m wide,
// 0.3 m deep, 1.7 m tall) standing on the floor at y = 0.6 m, about 1.2 m in front of the
// start pose, its centre at x = 1.8 m sin(w t), w such that its mean speed is `speed` (m/s).
// At t = 0 it stands in the middle of the start's view (a third of the image), and it is in
// view about a third of the time. Its colour is material `material` (makeScene with walker
// on: the last).
Box walkerAt(double speed, double t, int material);

// Nearest intersection with t > 0 of `ray` with the scene; false when the ray escapes.
bool intersect(const Scene& scene, const Ray& ray, Hit* hit);

// Many rays from one origin (a camera centre): what does not depend on the direction is
// computed once. Primitive p < quads.size() is quad p, otherwise box p - quads.size().
// The scene must outlive the caster.
class RayCaster {
 public:
  RayCaster(const Scene& scene, const Eigen::Vector3d& origin);

  int primitiveCount() const { return static_cast<int>(quads_.size() + boxes_.size()); }
  // Nearest hit along origin + t direction among `candidates` (ascending primitive indices;
  // nullptr = all). Same result as intersect() when the candidates include every primitive
  // the ray can hit.
  bool cast(const Eigen::Vector3d& direction, Hit* hit, const int* candidates = nullptr,
            int candidate_count = 0) const;

 private:
  struct PreparedQuad {
    Eigen::Vector3d normal;
    double numerator;  // normal . (centre - origin)
    Eigen::Vector3d axis_s, axis_t;
    double s0, t0;  // texture coordinates of the origin's projection
    double half_s, half_t;
  };
  struct PreparedBox {
    Eigen::Matrix3d world_to_box;  // rotation only
    Eigen::Vector3d origin;        // the ray origin in the box frame
    Eigen::Vector3d half_size;
  };
  bool castQuad(int index, const Eigen::Vector3d& d, double* t_best, Hit* hit) const;
  bool castBox(int index, const Eigen::Vector3d& direction, double* t_best, Hit* hit) const;

  const Scene* scene_;
  Eigen::Vector3d origin_;
  std::vector<PreparedQuad> quads_;
  std::vector<PreparedBox> boxes_;
};

}  // namespace acvo::synth
