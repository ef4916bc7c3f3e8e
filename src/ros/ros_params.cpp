#include "ros_params.hpp"

#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace acvo_ros {
namespace {

using XmlRpc::XmlRpcValue;

std::string typeProblem(const std::string& key, const char* expected) {
  return "~" + key + " must be " + expected + "; keeping its previous value";
}

std::string set(const std::string& key, const XmlRpcValue& v, int& field) {
  if (v.getType() != XmlRpcValue::TypeInt) return typeProblem(key, "an integer");
  field = static_cast<const int&>(v);
  return {};
}

std::string set(const std::string& key, const XmlRpcValue& v, double& field) {
  if (v.getType() == XmlRpcValue::TypeDouble) {
    field = static_cast<const double&>(v);
  } else if (v.getType() == XmlRpcValue::TypeInt) {
    field = static_cast<const int&>(v);
  } else {
    return typeProblem(key, "a number");
  }
  return {};
}

std::string set(const std::string& key, const XmlRpcValue& v, bool& field) {
  if (v.getType() != XmlRpcValue::TypeBoolean) return typeProblem(key, "true or false");
  field = static_cast<const bool&>(v);
  return {};
}

// The enums: a string parsed by the core's fromString.
template <typename Enum>
std::string set(const std::string& key, const XmlRpcValue& v, Enum& field) {
  if (v.getType() != XmlRpcValue::TypeString) return typeProblem(key, "a string");
  try {
    Enum parsed = field;
    acvo::fromString(static_cast<const std::string&>(v), parsed);
    field = parsed;
  } catch (const std::exception& e) {
    return "~" + key + ": " + e.what() + "; keeping its previous value";
  }
  return {};
}

}  // namespace

std::vector<std::string> applyRosParams(const XmlRpc::XmlRpcValue& private_ns,
                                        acvo::Params& params) {
  std::vector<std::string> problems;
  if (private_ns.getType() != XmlRpcValue::TypeStruct) return problems;
  // The keys the user set. A value of the wrong type is reported and dropped here (on a scratch
  // copy); the others are applied one at a time below.
  std::set<std::string> known;
  std::vector<std::pair<std::string, std::string>> given;  // (section, name)
  acvo::Params scratch = params;
  visitParams(scratch, [&](const std::string& section, const std::string& name, auto& field) {
    known.insert(section + "/" + name);
    if (!private_ns.hasMember(section)) return;
    const XmlRpcValue& values = private_ns[section];
    if (values.getType() != XmlRpcValue::TypeStruct || !values.hasMember(name)) return;
    std::string problem = set(section + "/" + name, values[name], field);
    if (problem.empty()) {
      given.emplace_back(section, name);
    } else {
      problems.push_back(problem);
    }
  });
  // Each given value alone on top of what is accepted so far; one that makes the set invalid
  // (a range, or an order with another parameter) is tried again after the others, in case a
  // partner it needs comes later (ell_min raised with ell_init), and otherwise rejected by
  // itself: every other value the user gave is kept.
  const auto with = [&](acvo::Params base, const std::pair<std::string, std::string>& key) {
    visitParams(base, [&](const std::string& section, const std::string& name, auto& field) {
      if (section == key.first && name == key.second) {
        set(section + "/" + name, private_ns[section][name], field);  // its type was checked
      }
    });
    return base;
  };
  acvo::Params accepted = params;
  for (bool progress = true; progress && !given.empty();) {
    progress = false;
    for (auto it = given.begin(); it != given.end();) {
      const acvo::Params trial = with(accepted, *it);
      if (acvo::validate(trial).empty()) {
        accepted = trial;
        it = given.erase(it);
        progress = true;
      } else {
        ++it;
      }
    }
  }
  for (const auto& key : given) {
    problems.push_back("~" + key.first + "/" + key.second + " rejected (" +
                       acvo::validate(with(accepted, key)) +
                       "); it keeps its default, the other parameters are used");
  }
  params = accepted;
  if (private_ns.hasMember("solver")) {
    problems.push_back("~solver was split (ignored): ~registration/engine chooses the engine, "
                       "~coarse_to_fine and ~paper hold each engine's parameters "
                       "(config/acvo.yaml, config/paper.yaml)");
  }
  for (const char* section : {"selection", "registration", "coarse_to_fine", "paper", "odometry"}) {
    if (!private_ns.hasMember(section)) continue;
    const XmlRpcValue& values = private_ns[section];
    if (values.getType() != XmlRpcValue::TypeStruct) {
      problems.push_back(std::string("~") + section + " must be a dictionary of parameters");
      continue;
    }
    for (const auto& kv : values) {
      const std::string key = std::string(section) + "/" + kv.first;
      if (!known.count(key)) {
        problems.push_back("unknown parameter ~" + key + " (ignored)" +
                           closeMatchHint(key, {known.begin(), known.end()}));
      }
    }
  }
  return problems;
}

std::string describeParams(const acvo::Params& params) {
  std::string out;
  for (const auto& [name, value] : acvo::paramTexts(params, '/')) {
    out += (out.empty() ? "" : " ") + name + "=" + value;
  }
  return out;
}

acvo::AcvoConfig toConfig(const acvo::Params& params, LostOdom lost_odom) {
  acvo::AcvoConfig c = acvo::AcvoConfig::__getDefault__();
  c.target_points = params.selection.target_points;
  c.min_depth = params.selection.min_depth;
  c.max_depth = params.selection.max_depth;
  c.engine = acvo::toString(params.registration.engine);
  c.ell_init = params.coarse_to_fine.ell_init;
  c.ell_min = params.coarse_to_fine.ell_min;
  c.color_ell = params.coarse_to_fine.color_ell;
  c.depth_noise = params.coarse_to_fine.depth_noise;
  c.level_iterations = params.coarse_to_fine.level_iterations;
  c.photometric = params.coarse_to_fine.photometric;
  c.point_to_plane = params.coarse_to_fine.point_to_plane;
  c.dense_point_to_plane = params.coarse_to_fine.dense_point_to_plane;
  c.photometric_gain = params.coarse_to_fine.photometric_gain;
  c.photometric_vignetting = params.coarse_to_fine.photometric_vignetting;
  c.exposure_time = params.coarse_to_fine.exposure_time;
  c.paper_ell_policy = acvo::toString(params.paper.ell_policy);
  c.paper_ell_init = params.paper.ell_init;
  c.paper_ell_min = params.paper.ell_min;
  c.paper_ell_max = params.paper.ell_max;
  c.paper_color_ell = params.paper.color_ell;
  c.paper_max_iterations = params.paper.max_iterations;
  c.initial_guess = acvo::toString(params.odometry.initial_guess);
  c.sync_depth = acvo::toString(params.odometry.sync_depth);
  c.unregistered_colour = acvo::toString(params.odometry.unregistered_colour);
  c.second_start = params.odometry.second_start;
  c.lost_odom = toString(lost_odom);
  return c;
}

acvo::Params fromConfig(const acvo::AcvoConfig& config, acvo::Params base) {
  base.selection.target_points = config.target_points;
  base.selection.min_depth = config.min_depth;
  base.selection.max_depth = config.max_depth;
  acvo::fromString(config.engine, base.registration.engine);
  base.coarse_to_fine.ell_init = config.ell_init;
  base.coarse_to_fine.ell_min = config.ell_min;
  base.coarse_to_fine.color_ell = config.color_ell;
  base.coarse_to_fine.depth_noise = config.depth_noise;
  base.coarse_to_fine.level_iterations = config.level_iterations;
  base.coarse_to_fine.photometric = config.photometric;
  base.coarse_to_fine.point_to_plane = config.point_to_plane;
  base.coarse_to_fine.dense_point_to_plane = config.dense_point_to_plane;
  base.coarse_to_fine.photometric_gain = config.photometric_gain;
  base.coarse_to_fine.photometric_vignetting = config.photometric_vignetting;
  base.coarse_to_fine.exposure_time = config.exposure_time;
  acvo::fromString(config.paper_ell_policy, base.paper.ell_policy);
  base.paper.ell_init = config.paper_ell_init;
  base.paper.ell_min = config.paper_ell_min;
  base.paper.ell_max = config.paper_ell_max;
  base.paper.color_ell = config.paper_color_ell;
  base.paper.max_iterations = config.paper_max_iterations;
  acvo::fromString(config.initial_guess, base.odometry.initial_guess);
  acvo::fromString(config.sync_depth, base.odometry.sync_depth);
  acvo::fromString(config.unregistered_colour, base.odometry.unregistered_colour);
  base.odometry.second_start = config.second_start;
  return base;
}

}  // namespace acvo_ros
