// makeScene: the furnished room (structure on) or the single plane (structure off), with
// seeded materials.
//
// Random draws are made one per statement or in braced lists (evaluated left to right):
// function arguments are evaluated in an unspecified order, and a seed must give the same
// scene with any compiler.
#include <cmath>
#include <limits>

#include "synth/layout.hpp"
#include "synth/random.hpp"
#include "synth/scene.hpp"

namespace acvo::synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Vector3d bgrFromHsv(double hue_deg, double s, double v) {
  const double h = std::fmod(std::fmod(hue_deg, 360.0) + 360.0, 360.0) / 60.0;
  const double c = v * s, x = c * (1.0 - std::abs(std::fmod(h, 2.0) - 1.0)), m = v - c;
  Eigen::Vector3d rgb;
  if (h < 1)
    rgb = {c, x, 0};
  else if (h < 2)
    rgb = {x, c, 0};
  else if (h < 3)
    rgb = {0, c, x};
  else if (h < 4)
    rgb = {0, x, c};
  else if (h < 5)
    rgb = {x, 0, c};
  else
    rgb = {c, 0, x};
  rgb.array() += m;
  return 255.0 * Eigen::Vector3d(rgb.z(), rgb.y(), rgb.x());
}

// A material drawn from `rng`; `pattern` and `period` say what overlay suits the surface.
Material makeMaterial(Rng& rng, bool textured, Pattern pattern, double period,
                      std::uint64_t noise_seed) {
  Material m;
  const double hsv_base[3] = {rng.uniform(0.0, 360.0), rng.uniform(0.25, 0.75),
                              rng.uniform(0.45, 0.9)};
  const double hsv_accent[3] = {hsv_base[0] + rng.uniform(40.0, 140.0), rng.uniform(0.2, 0.8),
                                rng.uniform(0.15, 0.6)};
  m.base = bgrFromHsv(hsv_base[0], hsv_base[1], hsv_base[2]);
  m.accent = bgrFromHsv(hsv_accent[0], hsv_accent[1], hsv_accent[2]);
  m.textured = textured;
  m.noise_wavelength = rng.uniform(0.6, 1.2);
  m.pattern = pattern;
  m.pattern_period = period * rng.uniform(0.8, 1.25);
  m.pattern_angle = rng.uniform(0.0, M_PI);
  m.pattern_contrast = rng.uniform(0.15, 0.3);
  m.seed = noise_seed;
  return m;
}

Quad makeQuad(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis_s,
              const Eigen::Vector3d& axis_t, double half_s, double half_t, int material) {
  Quad q;
  q.centre = centre;
  q.axis_s = axis_s.normalized();
  q.axis_t = axis_t.normalized();
  q.half_s = half_s;
  q.half_t = half_t;
  q.material = material;
  return q;
}

// Floor, ceiling and four walls, normals pointing into the room.
void addRoom(Scene& scene, int first_material) {
  const Eigen::Vector3d lo = kRoomMin, hi = kRoomMax, mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  int m = first_material;
  scene.quads.push_back(makeQuad({mid.x(), mid.y(), lo.z()}, X, Y, half.x(), half.y(), m++));
  scene.quads.push_back(makeQuad({mid.x(), mid.y(), hi.z()}, Y, X, half.y(), half.x(), m++));
  scene.quads.push_back(makeQuad({lo.x(), mid.y(), mid.z()}, Y, Z, half.y(), half.z(), m++));
  scene.quads.push_back(makeQuad({hi.x(), mid.y(), mid.z()}, Z, Y, half.z(), half.y(), m++));
  scene.quads.push_back(makeQuad({mid.x(), lo.y(), mid.z()}, Z, X, half.z(), half.x(), m++));
  scene.quads.push_back(makeQuad({mid.x(), hi.y(), mid.z()}, X, Z, half.x(), half.z(), m++));
}

Box makeBox(const Eigen::Vector3d& centre, const Eigen::Matrix3d& rotation,
            const Eigen::Vector3d& half_size, int material) {
  Box b;
  b.box_to_world.linear() = rotation;
  b.box_to_world.translation() = centre;
  b.half_size = half_size;
  b.material = material;
  return b;
}

Eigen::Matrix3d yaw(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// Boxes standing on the floor in the furniture region, one stacked on another, one tilted
// box hanging in the air, a board leaning back and a poster on the far wall.
void addFurniture(Scene& scene, Rng& rng, int first_material) {
  int m = first_material;
  constexpr int kFloorBoxes = 7;
  for (int i = 0; i < kFloorBoxes; ++i) {
    const Eigen::Vector3d half{rng.uniform(0.15, 0.5), rng.uniform(0.15, 0.5),
                               rng.uniform(0.15, 0.65)};
    const double reach = std::hypot(half.x(), half.y());  // footprint radius for any yaw
    const double x = rng.uniform(-kFurnitureHalfWidthX + reach, kFurnitureHalfWidthX - reach);
    const double y = rng.uniform(kFurnitureMinY + reach, kFurnitureMaxY - reach);
    scene.boxes.push_back(makeBox({x, y, half.z()}, yaw(rng.uniform(0.0, M_PI)), half, m++));
  }
  {  // a smaller box on top of a floor box
    const Box& base = scene.boxes[rng.index(kFloorBoxes)];
    const Eigen::Vector3d shrink{rng.uniform(0.4, 0.7), rng.uniform(0.4, 0.7),
                                 rng.uniform(0.5, 1.0)};
    const Eigen::Vector3d half = base.half_size.cwiseProduct(shrink);
    const Eigen::Vector3d centre =
        base.box_to_world.translation() + Eigen::Vector3d(0, 0, base.half_size.z() + half.z());
    scene.boxes.push_back(makeBox(centre, yaw(rng.uniform(0.0, M_PI)), half, m++));
  }
  {  // a box tilted about all three axes, in the air above the furniture
    const Eigen::Vector3d direction{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    const Eigen::Vector3d axis = direction.normalized();
    const Eigen::Matrix3d rotation =
        Eigen::AngleAxisd(rng.uniform(0.4, 1.2), axis).toRotationMatrix();
    const Eigen::Vector3d centre{rng.uniform(-1.5, 1.5), rng.uniform(1.2, 2.2),
                                 rng.uniform(1.6, 2.0)};
    scene.boxes.push_back(makeBox(centre, rotation, Eigen::Vector3d::Constant(0.25), m++));
  }
  {  // a board leaning back, its lower edge on the floor
    const double half_w = rng.uniform(0.4, 0.6), half_h = rng.uniform(0.5, 0.8);
    const double lean = rng.uniform(0.25, 0.6), heading = rng.uniform(-0.6, 0.6);
    const Eigen::Vector3d across = yaw(heading) * Eigen::Vector3d::UnitX();
    const Eigen::Vector3d back = yaw(heading) * Eigen::Vector3d::UnitY();
    const Eigen::Vector3d up = std::cos(lean) * Eigen::Vector3d::UnitZ() + std::sin(lean) * back;
    const Eigen::Vector3d foot{rng.uniform(-1.8, 1.8), rng.uniform(0.5, 2.0), 0.0};
    scene.quads.push_back(makeQuad(foot + half_h * up, across, up, half_w, half_h, m++));
  }
  {  // a poster a few centimetres in front of the far wall
    const Eigen::Vector3d centre{rng.uniform(-1.5, 1.5), kRoomMax.y() - 0.03,
                                 rng.uniform(1.2, 1.8)};
    const double half_w = rng.uniform(0.4, 0.7), half_h = rng.uniform(0.3, 0.5);
    scene.quads.push_back(
        makeQuad(centre, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), half_w, half_h, m++));
  }
}

// Materials: room surfaces first (floor, ceiling, walls x-, x+, y-, y+), then furniture.
void addMaterials(Scene& scene, Rng& rng, bool textured, std::uint64_t seed, int count) {
  for (int i = 0; i < count; ++i) {
    Pattern pattern = Pattern::kNone;
    double period = 0.25;
    if (i == 0) {
      pattern = Pattern::kChecker, period = 0.6;  // floor tiles
    } else if (i == 1) {
      pattern = Pattern::kNone;  // plain ceiling noise
    } else {
      const int kind = rng.index(3);
      pattern = kind == 0 ? Pattern::kNone : kind == 1 ? Pattern::kChecker : Pattern::kStripes;
      period = rng.uniform(0.08, 0.35);
    }
    scene.materials.push_back(
        makeMaterial(rng, textured, pattern, period, hashCombine(seed, 1000 + i)));
  }
}

}  // namespace

Scene makeScene(const SceneOptions& options) {
  Scene scene;
  Rng geometry(hashCombine(options.seed, 1));
  Rng colours(hashCombine(options.seed, 2));
  if (!options.structure) {
    scene.quads.push_back(makeQuad({0.0, kSinglePlaneY, 0.0}, Eigen::Vector3d::UnitX(),
                                   Eigen::Vector3d::UnitZ(), kInf, kInf, 0));
    scene.materials.push_back(makeMaterial(colours, options.texture, Pattern::kChecker, 0.2,
                                           hashCombine(options.seed, 1000)));
    return scene;
  }
  addRoom(scene, 0);
  addFurniture(scene, geometry, 6);
  const int used = static_cast<int>(scene.quads.size() + scene.boxes.size());
  addMaterials(scene, colours, options.texture, options.seed, used);
  if (options.walker) {  // from a stream of its own: the room's draws stay those of walker off
    Rng clothes(hashCombine(options.seed, 4));
    scene.materials.push_back(makeMaterial(clothes, options.texture, Pattern::kStripes, 0.15,
                                           hashCombine(options.seed, 1000 + used)));
  }
  return scene;
}

Box walkerAt(double speed, double t, int material) {
  constexpr double kReach = 1.8;  // m either side of the room's middle
  constexpr double kY = 0.6;
  const Eigen::Vector3d half{0.25, 0.15, 0.85};
  // The mean of |d/dt reach sin(w t)| is 2 reach w / pi.
  const double w = M_PI * speed / (2.0 * kReach);
  return makeBox({kReach * std::sin(w * t), kY, half.z()}, Eigen::Matrix3d::Identity(), half,
                 material);
}

}  // namespace acvo::synth
