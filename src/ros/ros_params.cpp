#include "ros_params.hpp"

#include <algorithm>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include <dynamic_reconfigure/Config.h>

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

namespace {

using Key = std::pair<std::string, std::string>;  // (section, name)

// The keys the user set, each of the right type; a value of the wrong type is reported (on a
// scratch copy) and left out. `known` gets every section/name there is.
std::vector<Key> givenValues(const XmlRpcValue& private_ns, const acvo::Params& params,
                             std::set<std::string>& known, std::vector<std::string>& problems) {
  std::vector<Key> given;
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
  return given;
}

// Each given value alone on top of what is accepted so far; one that makes the set invalid (a
// range, or an order with another parameter) is tried again after the others, in case a partner
// it needs comes later (ell_min raised with ell_init), and otherwise rejected by itself: every
// other value the user gave is kept.
acvo::Params applyEachAlone(const XmlRpcValue& private_ns, const acvo::Params& params,
                            std::vector<Key> given, std::vector<std::string>& problems) {
  const auto with = [&](acvo::Params base, const Key& key) {
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
  return accepted;
}

// Keys in the parameter sections that name no parameter, with the closest one that does; the
// old ~solver section.
void reportUnknown(const XmlRpcValue& private_ns, const std::set<std::string>& known,
                   std::vector<std::string>& problems) {
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
}

}  // namespace

std::vector<std::string> applyRosParams(const XmlRpc::XmlRpcValue& private_ns,
                                        acvo::Params& params) {
  std::vector<std::string> problems;
  if (private_ns.getType() != XmlRpcValue::TypeStruct) return problems;
  std::set<std::string> known;
  std::vector<Key> given = givenValues(private_ns, params, known, problems);
  params = applyEachAlone(private_ns, params, std::move(given), problems);
  reportUnknown(private_ns, known, problems);
  return problems;
}

namespace {

// Whether a private parameter's value is `field`'s (a number of either type for a double).
bool sameValue(const XmlRpcValue& v, bool field) {
  return v.getType() == XmlRpcValue::TypeBoolean && static_cast<const bool&>(v) == field;
}
bool sameValue(const XmlRpcValue& v, int field) {
  return v.getType() == XmlRpcValue::TypeInt && static_cast<const int&>(v) == field;
}
bool sameValue(const XmlRpcValue& v, double field) {
  if (v.getType() == XmlRpcValue::TypeDouble) return static_cast<const double&>(v) == field;
  return v.getType() == XmlRpcValue::TypeInt && static_cast<const int&>(v) == field;
}
template <typename Enum>
bool sameValue(const XmlRpcValue& v, Enum field) {
  return v.getType() == XmlRpcValue::TypeString &&
         static_cast<const std::string&>(v) == acvo::toString(field);
}

// A private parameter's value as the user wrote it, for a message.
std::string valueText(const XmlRpcValue& v) {
  std::ostringstream out;
  switch (v.getType()) {
    case XmlRpcValue::TypeBoolean:
      out << (static_cast<const bool&>(v) ? "true" : "false");
      break;
    case XmlRpcValue::TypeInt:
      out << static_cast<const int&>(v);
      break;
    case XmlRpcValue::TypeDouble:
      out << static_cast<const double&>(v);
      break;
    case XmlRpcValue::TypeString:
      out << "'" << static_cast<const std::string&>(v) << "'";
      break;
    default:
      out << "(not a single value)";
  }
  return out.str();
}

// The reconfigure name of a parameter: its key, the paper section's with a paper_ prefix
// (dynamic_reconfigure's names are one flat namespace). The .cfg is the one table of what is
// reconfigurable; toConfig and fromConfig carry every parameter it names, by that name.
std::string reconfigureName(const std::string& section, const std::string& key) {
  return section == "paper" ? "paper_" + key : key;
}

std::set<std::string> cfgNames() {
  std::set<std::string> names;
  for (const auto& d : acvo::AcvoConfig::__getParamDescriptions__()) names.insert(d->name);
  return names;
}

}  // namespace

std::vector<std::string> sectionlessParameters(const XmlRpc::XmlRpcValue& private_ns,
                                               const acvo::Params& params) {
  std::vector<std::string> problems;
  if (private_ns.getType() != XmlRpcValue::TypeStruct) return problems;
  const std::set<std::string> reconfigurable = cfgNames();
  // Per top-level name found: the parameters it may stand for, and whether its value is the
  // one in use of the parameter the reconfigure server shows under that name.
  struct Found {
    std::vector<std::string> keys;  // "section/key"
    std::string reconfigured;       // the key the server shows under this name, if any
    bool servers_own = false;
  };
  std::map<std::string, Found> found;
  acvo::visitParams(params, [&](const std::string& section, const std::string& key,
                                const auto& field) {
    const std::string reconfigure = reconfigureName(section, key);
    for (const std::string& name : {key, reconfigure}) {
      if (!private_ns.hasMember(name)) continue;
      Found& f = found[name];
      const std::string full = section + "/" + key;
      if (std::find(f.keys.begin(), f.keys.end(), full) == f.keys.end()) f.keys.push_back(full);
      if (name == reconfigure && reconfigurable.count(name)) {
        f.reconfigured = full;
        f.servers_own = sameValue(private_ns[name], field);
      }
    }
  });
  for (const auto& [name, f] : found) {
    if (f.servers_own) continue;
    std::string keys;
    for (std::size_t k = 0; k < f.keys.size(); ++k) {
      keys += (k == 0 ? "~" : " or ~") + f.keys[k];
    }
    std::string problem = "~" + name + " = " + valueText(private_ns[name]) +
                          " is not read (ignored): the parameter is " + keys;
    if (!f.reconfigured.empty()) {
      problem += "; dynamic_reconfigure shows ~" + f.reconfigured + " as " + name +
                 " and starts it from ~" + f.reconfigured + ", not from ~" + name;
    }
    problems.push_back(problem);
  }
  return problems;
}

std::vector<std::string> sectionlessNames() {
  std::set<std::string> names;
  const acvo::Params defaults;
  acvo::visitParams(defaults, [&](const std::string& section, const std::string& key,
                                  const auto&) {
    names.insert(key);
    names.insert(reconfigureName(section, key));
  });
  return {names.begin(), names.end()};
}

std::string describeParams(const acvo::Params& params) {
  std::string out;
  for (const auto& [name, value] : acvo::paramTexts(params, '/')) {
    out += (out.empty() ? "" : " ") + name + "=" + value;
  }
  return out;
}

namespace {

template <typename Entry, typename Value>
void put(std::vector<Entry>& entries, const std::string& name, const Value& value) {
  Entry e;
  e.name = name;
  e.value = value;
  entries.push_back(e);
}

template <typename Entry>
const Entry* entryNamed(const std::vector<Entry>& entries, const std::string& name) {
  for (const Entry& e : entries) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

}  // namespace

acvo::AcvoConfig toConfig(const acvo::Params& params, LostOdom lost_odom) {
  const std::set<std::string> named = cfgNames();
  dynamic_reconfigure::Config msg;
  acvo::visitParams(params, [&](const std::string& section, const std::string& key,
                                const auto& field) {
    using T = std::decay_t<decltype(field)>;
    const std::string name = reconfigureName(section, key);
    if (!named.count(name)) return;
    if constexpr (std::is_same_v<T, bool>) {
      put(msg.bools, name, field);
    } else if constexpr (std::is_same_v<T, int>) {
      put(msg.ints, name, field);
    } else if constexpr (std::is_same_v<T, double>) {
      put(msg.doubles, name, field);
    } else {
      put(msg.strs, name, acvo::toString(field));
    }
  });
  put(msg.strs, "lost_odom", toString(lost_odom));
  // Only the entries the .cfg names: __fromMessage__ takes them and logs an error for any other.
  acvo::AcvoConfig config = acvo::AcvoConfig::__getDefault__();
  if (!config.__fromMessage__(msg)) {
    throw std::logic_error("toConfig: a parameter the .cfg does not name reached the message");
  }
  return config;
}

acvo::Params fromConfig(const acvo::AcvoConfig& config, acvo::Params base) {
  dynamic_reconfigure::Config msg;
  config.__toMessage__(msg);
  acvo::visitParams(base, [&](const std::string& section, const std::string& key, auto& field) {
    using T = std::decay_t<decltype(field)>;
    const std::string name = reconfigureName(section, key);
    if constexpr (std::is_same_v<T, bool>) {
      if (const auto* e = entryNamed(msg.bools, name)) field = e->value != 0;
    } else if constexpr (std::is_same_v<T, int>) {
      if (const auto* e = entryNamed(msg.ints, name)) field = e->value;
    } else if constexpr (std::is_same_v<T, double>) {
      if (const auto* e = entryNamed(msg.doubles, name)) field = e->value;
    } else {
      if (const auto* e = entryNamed(msg.strs, name)) acvo::fromString(e->value, field);
    }
  });
  return base;
}

std::vector<std::string> reconfigureNamesWithoutParameter() {
  std::set<std::string> names;
  const acvo::Params defaults;
  acvo::visitParams(defaults, [&](const std::string& section, const std::string& key,
                                  const auto&) { names.insert(reconfigureName(section, key)); });
  std::vector<std::string> missing;
  for (const auto& d : acvo::AcvoConfig::__getParamDescriptions__()) {
    if (d->name != "lost_odom" && !names.count(d->name)) missing.push_back(d->name);
  }
  return missing;
}

}  // namespace acvo_ros
