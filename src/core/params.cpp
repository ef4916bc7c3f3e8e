#include "acvo/params.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <yaml-cpp/yaml.h>

namespace acvo {
namespace {

// One table per enum: the spelling used in YAML, on the ROS parameter server and in logs.
template <typename Enum>
struct EnumNames;

template <>
struct EnumNames<EllPolicy> {
  static constexpr std::pair<EllPolicy, const char*> table[] = {
      {EllPolicy::kAdaptive, "adaptive"},
      {EllPolicy::kFixedSchedule, "fixed_schedule"},
      {EllPolicy::kCoarseToFine, "coarse_to_fine"}};
};
template <>
struct EnumNames<EllUpdate> {
  static constexpr std::pair<EllUpdate, const char*> table[] = {
      {EllUpdate::kDescent, "descent"}, {EllUpdate::kReference, "reference"}};
};
template <>
struct EnumNames<InitialGuess> {
  static constexpr std::pair<InitialGuess, const char*> table[] = {
      {InitialGuess::kConstantVelocity, "constant_velocity"},
      {InitialGuess::kIdentity, "identity"}};
};

template <>
struct EnumNames<SearchDirection> {
  static constexpr std::pair<SearchDirection, const char*> table[] = {
      {SearchDirection::kConjugateGradient, "conjugate_gradient"},
      {SearchDirection::kGradient, "gradient"}};
};

template <>
struct EnumNames<Reference> {
  static constexpr std::pair<Reference, const char*> table[] = {
      {Reference::kKeyframe, "keyframe"}, {Reference::kPreviousFrame, "previous_frame"}};
};

template <typename Enum>
std::string enumToString(Enum v) {
  for (const auto& [value, name] : EnumNames<Enum>::table) {
    if (value == v) return name;
  }
  throw std::invalid_argument("enum value out of range: " + std::to_string(static_cast<int>(v)));
}

template <typename Enum>
void enumFromString(const std::string& s, Enum& v) {
  std::string accepted;
  for (const auto& [value, name] : EnumNames<Enum>::table) {
    if (s == name) {
      v = value;
      return;
    }
    accepted += accepted.empty() ? "" : ", ";
    accepted += std::string("\"") + name + "\"";
  }
  throw std::invalid_argument("\"" + s + "\" is not one of " + accepted);
}

template <typename T>
constexpr bool kIsEnum = std::is_enum_v<T>;

// Reads one scalar into a field of the type visitParams hands over; throws a message saying
// what was expected (the caller adds the file and key).
template <typename T>
void readScalar(const YAML::Node& node, T& field) {
  if (!node.IsScalar()) throw std::invalid_argument("expected a scalar value");
  const std::string text = node.Scalar();
  if constexpr (kIsEnum<T>) {
    fromString(text, field);
  } else {
    T value{};
    if (!YAML::convert<T>::decode(node, value)) {
      const char* what = std::is_same_v<T, bool>  ? "a boolean (true/false)"
                         : std::is_same_v<T, int> ? "an integer"
                                                  : "a number";
      throw std::invalid_argument("expected " + std::string(what) + ", got \"" + text + "\"");
    }
    field = value;
  }
}

void check(std::ostringstream& why, bool ok, const char* key, const std::string& what) {
  if (!ok && why.tellp() == 0) why << key << " " << what;
}

}  // namespace

std::string toString(EllPolicy v) {
  return enumToString(v);
}
std::string toString(EllUpdate v) {
  return enumToString(v);
}
std::string toString(InitialGuess v) {
  return enumToString(v);
}
std::string toString(SearchDirection v) {
  return enumToString(v);
}
std::string toString(Reference v) {
  return enumToString(v);
}
void fromString(const std::string& s, EllPolicy& v) {
  enumFromString(s, v);
}
void fromString(const std::string& s, EllUpdate& v) {
  enumFromString(s, v);
}
void fromString(const std::string& s, InitialGuess& v) {
  enumFromString(s, v);
}
void fromString(const std::string& s, SearchDirection& v) {
  enumFromString(s, v);
}
void fromString(const std::string& s, Reference& v) {
  enumFromString(s, v);
}

std::string validate(const Params& p) {
  std::ostringstream why;
  // Every floating-point parameter must be finite before any ordering check means anything.
  visitParams(p, [&why](const char* section, const char* name, const auto& field) {
    if constexpr (std::is_floating_point_v<std::decay_t<decltype(field)>>) {
      if (!std::isfinite(field) && why.tellp() == 0) {
        why << section << "." << name << " must be finite";
      }
    }
  });
  const SelectionParams& se = p.selection;
  const SolverParams& so = p.solver;
  check(why, se.target_points > 0, "selection.target_points", "must be positive");
  check(why, se.min_depth >= 0.0, "selection.min_depth", "must not be negative");
  check(why, se.min_depth < se.max_depth, "selection.min_depth", "must be below max_depth");
  check(why, so.ell_min > 0.0, "solver.ell_min", "must be positive");
  check(why, so.ell_min <= so.ell_max, "solver.ell_min", "must not exceed ell_max");
  check(why, so.ell_init >= so.ell_min && so.ell_init <= so.ell_max, "solver.ell_init",
        "must lie within [ell_min, ell_max]");
  check(why, so.ell_step > 0.0, "solver.ell_step", "must be positive");
  check(why, so.ell_reduction > 0.0 && so.ell_reduction < 1.0, "solver.ell_reduction",
        "must lie in (0, 1)");
  check(why, so.sigma > 0.0, "solver.sigma", "must be positive");
  check(why, so.color_ell > 0.0, "solver.color_ell", "must be positive");
  check(why, so.color_sigma > 0.0, "solver.color_sigma", "must be positive");
  check(why, so.sparsification > 0.0, "solver.sparsification", "must be positive");
  // a_ij never exceeds sigma^2 * color_sigma^2: a threshold at or above it drops every pair.
  check(why, so.sparsification < so.sigma * so.sigma * so.color_sigma * so.color_sigma,
        "solver.sparsification", "must be below sigma^2 * color_sigma^2");
  check(why, so.eps_transform > 0.0, "solver.eps_transform", "must be positive");
  check(why, so.eps_gradient > 0.0, "solver.eps_gradient", "must be positive");
  check(why, so.min_step > 0.0, "solver.min_step", "must be positive");
  check(why, so.min_step <= so.max_step, "solver.min_step", "must not exceed max_step");
  check(why, so.omega_scale > 0.0, "solver.omega_scale", "must be positive");
  check(why, so.v_scale > 0.0, "solver.v_scale", "must be positive");
  check(why, so.max_iterations > 0, "solver.max_iterations", "must be positive");
  check(why, so.stall_iterations >= 0, "solver.stall_iterations", "must not be negative");
  check(why, so.min_points > 0, "solver.min_points", "must be positive");
  check(why, so.coarse_ell >= 0.0, "solver.coarse_ell", "must not be negative (0 = off)");
  check(why, so.coarse_points > 0, "solver.coarse_points", "must be positive");
  check(why, so.coarse_iterations >= 0, "solver.coarse_iterations", "must not be negative");
  check(why, so.ell_depth_reference >= 0.0, "solver.ell_depth_reference",
        "must not be negative (0 = off)");
  check(why, so.depth_noise >= 0.0, "solver.depth_noise", "must not be negative (0 = off)");
  check(why, so.level_points > 0, "solver.level_points", "must be positive");
  check(why, so.level_iterations > 0, "solver.level_iterations", "must be positive");
  check(why, so.level_eps > 0.0, "solver.level_eps", "must be positive");
  check(why, so.level_acceleration >= 0.0 && so.level_acceleration < 1.0,
        "solver.level_acceleration", "must lie in [0, 1)");
  const OdometryParams& od = p.odometry;
  check(why, od.threads >= 0, "odometry.threads", "must not be negative (0 = all cores)");
  check(why,
        od.lost_matched_fraction >= 0.0 && od.lost_matched_fraction <= od.hard_matched_fraction,
        "odometry.lost_matched_fraction", "must lie within [0, hard_matched_fraction]");
  check(why, od.hard_matched_fraction <= 1.0, "odometry.hard_matched_fraction",
        "must not exceed 1");
  check(why, od.max_translation > 0.0, "odometry.max_translation", "must be positive");
  check(why, od.max_rotation > 0.0, "odometry.max_rotation", "must be positive");
  check(why, od.hard_ell_reductions > 0, "odometry.hard_ell_reductions", "must be positive");
  check(why, od.covariance_scale > 0.0, "odometry.covariance_scale", "must be positive");
  check(why, od.keyframe_matched_fraction >= 0.0 && od.keyframe_matched_fraction <= 1.0,
        "odometry.keyframe_matched_fraction", "must lie within [0, 1]");
  check(why, od.keyframe_translation > 0.0, "odometry.keyframe_translation", "must be positive");
  check(why, od.keyframe_rotation > 0.0, "odometry.keyframe_rotation", "must be positive");
  check(why, od.lost_speed >= 0.0, "odometry.lost_speed", "must not be negative");
  check(why, od.lost_angular_speed >= 0.0, "odometry.lost_angular_speed", "must not be negative");
  return why.str();
}

Params paperParams() {
  Params p;
  p.selection.target_points = 3000;
  p.selection.max_depth = 6.0;
  p.solver.ell_policy = EllPolicy::kAdaptive;
  p.solver.ell_init = 0.1;
  p.solver.ell_min = 0.0391;
  p.solver.ell_reduction = 0.7;
  p.solver.sparsification = 8.315e-3;
  p.solver.ell_depth_reference = 0.0;
  p.solver.depth_noise = 0.0;
  p.odometry.reference = Reference::kPreviousFrame;  // the paper's frame-to-frame driver
  p.odometry.lost_matched_fraction = 0.02;
  p.odometry.hard_matched_fraction = 0.05;
  p.odometry.covariance_scale = 6e-4;
  return p;
}

Params parseParams(const std::string& yaml_text, const Params& base,
                   const std::string& source_name) {
  auto fail = [&source_name](const std::string& what) {
    return std::runtime_error(source_name + ": " + what);
  };
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw fail(std::string("YAML syntax error: ") + e.what());
  }
  Params p = base;
  if (root.IsNull()) return p;  // an empty file keeps every default
  if (!root.IsMap()) throw fail("expected a map of sections (selection, solver, odometry)");

  for (const auto& section : root) {
    const std::string section_name = section.first.as<std::string>();
    bool known_section = false;
    visitParams(p, [&](const char* s, const char*, auto&) { known_section |= section_name == s; });
    if (!known_section) {
      throw fail("unknown section '" + section_name + "' (expected selection, solver or odometry)");
    }
    if (section.second.IsNull()) continue;
    if (!section.second.IsMap()) throw fail("section '" + section_name + "' must be a map");

    for (const auto& entry : section.second) {
      const std::string key = entry.first.as<std::string>();
      const std::string full_key = section_name + "." + key;
      bool found = false;
      visitParams(p, [&](const char* s, const char* name, auto& field) {
        if (found || section_name != s || key != name) return;
        found = true;
        try {
          readScalar(entry.second, field);
        } catch (const std::exception& e) {
          throw fail("bad value for '" + full_key + "': " + e.what());
        }
      });
      if (!found) throw fail("unknown key '" + full_key + "'");
    }
  }
  if (const std::string why = validate(p); !why.empty()) throw fail(why);
  return p;
}

Params loadParams(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the parameter file");
  std::stringstream text;
  text << in.rdbuf();
  return parseParams(text.str(), Params(), path);
}

}  // namespace acvo
