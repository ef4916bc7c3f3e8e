#include "nodelet_settings.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace acvo_ros {
namespace {

using XmlRpc::XmlRpcValue;

std::string wrongType(const std::string& key, const char* expected) {
  return "~" + key + " must be " + expected + "; keeping its previous value";
}

// Each reader leaves `field` alone when the key is absent, and reports a wrong type.
template <typename T>
void readAs(const XmlRpcValue& ns, const std::string& key, T& field, XmlRpcValue::Type type,
            const char* type_name, std::vector<std::string>& problems) {
  if (!ns.hasMember(key)) return;
  const XmlRpcValue& v = ns[key];
  if (v.getType() != type) {
    problems.push_back(wrongType(key, type_name));
    return;
  }
  field = static_cast<const T&>(v);
}

void read(const XmlRpcValue& ns, const std::string& key, std::string& field,
          std::vector<std::string>& problems) {
  readAs(ns, key, field, XmlRpcValue::TypeString, "a string", problems);
}

void read(const XmlRpcValue& ns, const std::string& key, bool& field,
          std::vector<std::string>& problems) {
  readAs(ns, key, field, XmlRpcValue::TypeBoolean, "true or false", problems);
}

void read(const XmlRpcValue& ns, const std::string& key, int& field,
          std::vector<std::string>& problems) {
  readAs(ns, key, field, XmlRpcValue::TypeInt, "an integer", problems);
}

// A number may be written as an integer.
void read(const XmlRpcValue& ns, const std::string& key, double& field,
          std::vector<std::string>& problems) {
  if (!ns.hasMember(key)) return;
  const XmlRpcValue& v = ns[key];
  if (v.getType() == XmlRpcValue::TypeDouble) {
    field = static_cast<const double&>(v);
  } else if (v.getType() == XmlRpcValue::TypeInt) {
    field = static_cast<const int&>(v);
  } else {
    problems.push_back(wrongType(key, "a number"));
  }
}

// A number read into `field` only when it satisfies `ok` (said by `range`).
template <typename T, typename Ok>
void readChecked(const XmlRpcValue& ns, const std::string& key, T& field, Ok ok, const char* range,
                 std::vector<std::string>& problems) {
  T value = field;
  read(ns, key, value, problems);
  if (ok(value)) {
    field = value;
  } else {
    std::ostringstream out;
    out << "~" << key << " = " << value << " must be " << range << "; keeping " << field;
    problems.push_back(out.str());
  }
}

std::string frameId(const XmlRpcValue& ns, const std::string& key, const std::string& initial,
                    std::vector<std::string>& problems) {
  std::string id = initial;
  read(ns, key, id, problems);
  return stripSlash(id);
}

// The settings loadNodeletSettings reads, and the other top-level keys the nodelet reads.
const char* const kTopLevelKeys[] = {
    "odom_frame_id", "base_frame_id", "guess_frame_id", "base_is_optical_frame", "publish_tf",
    "approx_sync", "wait_for_transform_duration", "max_time_gap", "no_data_timeout",
    "approx_sync_max_interval", "topic_queue_size", "queue_size", "sync_queue_size", "lost_odom",
    "publish_null_when_lost", "camera", "fx", "fy", "cx", "cy", "initial_pose",
    // the parameter sections (ros_params.hpp), the old one it reports, the transport hints
    "selection", "registration", "coarse_to_fine", "paper", "odometry", "solver", "image_transport",
    "depth_image_transport",
    // diagnostic_updater's own (it reads it from the same private namespace)
    "diagnostic_period"};

// Other nodes' names for a setting, and what it is here.
const std::pair<const char*, const char*> kAliases[] = {
    {"frame_id", "base_frame_id"},
    {"child_frame_id", "base_frame_id"},
    {"wait_for_transform", "wait_for_transform_duration"},
    {"rgb/image_transport", "image_transport"},
    {"depth/image_transport", "depth_image_transport"},
    {"publish_tf_odom", "publish_tf"},
};

// Levenshtein distance (two rows). Written out: none of the libraries here offers one for
// strings, and a dozen lines beat a dependency.
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitute = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, substitute});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace

std::string closeMatchHint(const std::string& name, const std::vector<std::string>& known) {
  const std::size_t allowed = std::max<std::size_t>(2, name.size() / 3);
  std::size_t best = allowed + 1;
  std::string match;
  for (const std::string& k : known) {
    const std::size_t d = editDistance(name, k);
    if (d < best) {
      best = d;
      match = k;
    }
  }
  return match.empty() ? std::string() : " (did you mean ~" + match + "?)";
}

std::vector<std::string> unknownParameters(const XmlRpc::XmlRpcValue& private_ns,
                                           const std::vector<std::string>& also_known) {
  std::vector<std::string> problems;
  if (private_ns.getType() != XmlRpcValue::TypeStruct) return problems;
  std::vector<std::string> known(std::begin(kTopLevelKeys), std::end(kTopLevelKeys));
  known.insert(known.end(), also_known.begin(), also_known.end());
  const auto report = [&](const std::string& name) {
    for (const auto& [alias, here] : kAliases) {
      if (name == alias) {
        problems.push_back("unknown parameter ~" + name + " (ignored): this node calls it ~" +
                           here);
        return;
      }
    }
    if (name.rfind("Odom", 0) == 0 || name.rfind("Reg/", 0) == 0 || name.rfind("Vis/", 0) == 0) {
      problems.push_back("unknown parameter ~" + name +
                         " (ignored): rtabmap's parameters are not read here; acvo's are "
                         "~selection/, ~registration/, ~coarse_to_fine/ and ~odometry/ "
                         "(config/acvo.yaml)");
      return;
    }
    problems.push_back("unknown parameter ~" + name + " (ignored)" + closeMatchHint(name, known));
  };
  for (const auto& [key, value] : private_ns) {
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    if (value.getType() == XmlRpcValue::TypeStruct && value.size() > 0) {
      // A namespace of its own (rgb/image_transport, rtabmap's Odom/Strategy): name its keys.
      for (const auto& inner : value) report(key + "/" + inner.first);
    } else {
      report(key);
    }
  }
  return problems;
}

std::string toString(LostOdom v) {
  switch (v) {
    case LostOdom::kHeld:
      return "held";
    case LostOdom::kNull:
      return "null";
    case LostOdom::kNone:
      return "none";
  }
  return "held";
}

void fromString(const std::string& s, LostOdom& v) {
  for (LostOdom c : {LostOdom::kHeld, LostOdom::kNull, LostOdom::kNone}) {
    if (s == toString(c)) {
      v = c;
      return;
    }
  }
  throw std::invalid_argument("'" + s + "' is not one of held, null, none");
}

std::optional<Eigen::Isometry3d> parsePose6(const std::string& text, std::string* problem) {
  std::istringstream in(text);
  double v[6];
  int n = 0;
  while (n < 6 && in >> v[n]) ++n;
  std::string rest;
  const bool trailing = static_cast<bool>(in >> rest) || (!in.eof() && n < 6);
  bool finite = true;
  for (int k = 0; k < n; ++k) finite = finite && std::isfinite(v[k]);
  if (n != 6 || trailing || !finite) {
    if (problem) {
      *problem =
          "'" + text + "' is not six finite numbers \"x y z roll pitch yaw\" (metres, radians)";
    }
    return std::nullopt;
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                      .matrix();
  pose.translation() << v[0], v[1], v[2];
  if (problem) problem->clear();
  return pose;
}

namespace {

// Frames, switches, durations and queue sizes.
void readFramesAndQueues(const XmlRpcValue& ns, NodeletSettings& s,
                         std::vector<std::string>& problems) {
  s.odom_frame_id = frameId(ns, "odom_frame_id", s.odom_frame_id, problems);
  s.base_frame_id = frameId(ns, "base_frame_id", s.base_frame_id, problems);
  s.guess_frame_id = frameId(ns, "guess_frame_id", s.guess_frame_id, problems);
  read(ns, "base_is_optical_frame", s.base_is_optical_frame, problems);
  read(ns, "publish_tf", s.publish_tf, problems);
  read(ns, "approx_sync", s.approx_sync, problems);
  const auto non_negative = [](double v) { return v >= 0.0 && std::isfinite(v); };
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  const auto at_least_one = [](int v) { return v >= 1; };
  readChecked(ns, "wait_for_transform_duration", s.wait_for_transform_duration, non_negative,
              ">= 0", problems);
  readChecked(ns, "max_time_gap", s.max_time_gap, positive, "> 0", problems);
  readChecked(ns, "no_data_timeout", s.no_data_timeout, positive, "> 0", problems);
  readChecked(ns, "approx_sync_max_interval", s.approx_sync_max_interval, non_negative, ">= 0",
              problems);
  readChecked(ns, "topic_queue_size", s.topic_queue_size, at_least_one, ">= 1", problems);
  if (ns.hasMember("queue_size")) {
    // The old single queue size: now the synchroniser's (as rtabmap renamed it).
    const bool has_new = ns.hasMember("sync_queue_size");
    int old = s.sync_queue_size;
    readChecked(ns, "queue_size", old, at_least_one, ">= 1", problems);
    if (!has_new) s.sync_queue_size = old;
    problems.push_back(std::string("~queue_size is now ~sync_queue_size (the subscriber queues "
                                   "are ~topic_queue_size)") +
                       (has_new ? "; ~sync_queue_size is set too and wins"
                                : "; taken as ~sync_queue_size = " + std::to_string(old)));
  }
  readChecked(ns, "sync_queue_size", s.sync_queue_size, at_least_one, ">= 1", problems);
}

// ~lost_odom, and rtabmap's ~publish_null_when_lost for it.
void readLostOdom(const XmlRpcValue& ns, NodeletSettings& s, std::vector<std::string>& problems) {
  if (ns.hasMember("lost_odom")) {
    std::string text = toString(s.lost_odom);
    read(ns, "lost_odom", text, problems);
    try {
      fromString(text, s.lost_odom);
    } catch (const std::exception& e) {
      problems.push_back(std::string("~lost_odom: ") + e.what() + "; keeping " +
                         toString(s.lost_odom));
    }
  }
  if (ns.hasMember("publish_null_when_lost")) {
    // rtabmap's parameter, with rtabmap's meaning; lost_odom says the same with three values.
    bool null_when_lost = false;
    std::vector<std::string> type_problems;
    read(ns, "publish_null_when_lost", null_when_lost, type_problems);
    problems.insert(problems.end(), type_problems.begin(), type_problems.end());
    if (type_problems.empty()) {
      if (ns.hasMember("lost_odom")) {
        problems.push_back("~publish_null_when_lost is ignored: ~lost_odom is set");
      } else {
        s.lost_odom = null_when_lost ? LostOdom::kNull : LostOdom::kNone;
        problems.push_back(
            std::string("~publish_null_when_lost (rtabmap's meaning) is ~lost_odom here: taken "
                        "as lost_odom = ") +
            toString(s.lost_odom) + " (the default, held, publishes the held pose)");
      }
    }
  }
}

// ~camera, ~fx, ~fy, ~cx, ~cy: kept only as a whole that makes sense.
void readIntrinsics(const XmlRpcValue& ns, NodeletSettings& s, std::vector<std::string>& problems) {
  IntrinsicsOverride intrinsics = s.intrinsics;
  read(ns, "camera", intrinsics.camera, problems);
  read(ns, "fx", intrinsics.fx, problems);
  read(ns, "fy", intrinsics.fy, problems);
  read(ns, "cx", intrinsics.cx, problems);
  read(ns, "cy", intrinsics.cy, problems);
  if (const std::string why = intrinsics.problem(); !why.empty()) {
    problems.push_back(why + ": ignoring the override, intrinsics come from camera_info");
  } else {
    s.intrinsics = intrinsics;
  }
}

// ~initial_pose: "x y z roll pitch yaw" as a string or a list of numbers.
void readInitialPose(const XmlRpcValue& ns, NodeletSettings& s,
                     std::vector<std::string>& problems) {
  if (ns.hasMember("initial_pose")) {
    const XmlRpcValue& v = ns["initial_pose"];
    std::string text;
    if (v.getType() == XmlRpcValue::TypeString) {
      text = static_cast<const std::string&>(v);
    } else if (v.getType() == XmlRpcValue::TypeArray) {
      std::ostringstream out;
      out.precision(17);
      for (int k = 0; k < v.size(); ++k) {
        const XmlRpcValue& e = v[k];
        if (e.getType() == XmlRpcValue::TypeDouble) {
          out << static_cast<const double&>(e) << ' ';
        } else if (e.getType() == XmlRpcValue::TypeInt) {
          out << static_cast<const int&>(e) << ' ';
        } else {
          out << "? ";
        }
      }
      text = out.str();
    } else {
      text = "?";
    }
    if (text.find_first_not_of(" \t") != std::string::npos) {
      std::string why;
      const std::optional<Eigen::Isometry3d> pose = parsePose6(text, &why);
      if (pose) {
        s.initial_pose = pose;
      } else {
        problems.push_back("~initial_pose " + why + ": starting at the origin");
      }
    }
  }
}

// Combinations that cannot work, undone with a reason.
void checkCombinations(NodeletSettings& s, std::vector<std::string>& problems) {
  if (!s.guess_frame_id.empty()) {
    const std::string base = s.base_frame_id;
    std::string why;
    if (s.guess_frame_id == s.odom_frame_id) {
      why =
          "is odom_frame_id: the correction odom_frame_id -> guess_frame_id would be a loop "
          "(use e.g. odom_frame_id vo, guess_frame_id odom)";
    } else if (s.guess_frame_id == base) {
      why = "is the base frame";
    } else if (s.base_is_optical_frame) {
      why = "needs a base frame in TF, and base_is_optical_frame names one that is not";
    }
    if (!why.empty()) {
      problems.push_back("~guess_frame_id '" + s.guess_frame_id + "' " + why +
                         ": no guess from TF (constant velocity)");
      s.guess_frame_id.clear();
    }
  }
  if (s.base_is_optical_frame && s.base_frame_id.empty()) {
    problems.push_back(
        "~base_is_optical_frame needs a base_frame_id to name the estimate: "
        "using the colour image's frame");
    s.base_is_optical_frame = false;
  }
}

}  // namespace

std::vector<std::string> loadNodeletSettings(const XmlRpc::XmlRpcValue& private_ns,
                                             NodeletSettings& s) {
  std::vector<std::string> problems;
  if (private_ns.getType() != XmlRpcValue::TypeStruct) return problems;
  readFramesAndQueues(private_ns, s, problems);
  readLostOdom(private_ns, s, problems);
  readIntrinsics(private_ns, s, problems);
  readInitialPose(private_ns, s, problems);
  checkCombinations(s, problems);
  return problems;
}

std::string describe(const NodeletSettings& s) {
  std::ostringstream out;
  out << "odom_frame_id=" << s.odom_frame_id
      << " base_frame_id=" << (s.base_frame_id.empty() ? "(the image's)" : s.base_frame_id)
      << (s.base_is_optical_frame ? " (optical)" : "")
      << " guess_frame_id=" << (s.guess_frame_id.empty() ? "(none)" : s.guess_frame_id)
      << " publish_tf=" << (s.publish_tf ? "true" : "false")
      << " lost_odom=" << toString(s.lost_odom) << " sync=" << (s.approx_sync ? "approx" : "exact")
      << " topic_queue_size=" << s.topic_queue_size << " sync_queue_size=" << s.sync_queue_size
      << " wait_for_transform_duration=" << s.wait_for_transform_duration;
  if (s.initial_pose) {
    const Eigen::Vector3d t = s.initial_pose->translation();
    out << " initial_pose=" << t.x() << "," << t.y() << "," << t.z();
  }
  return out.str();
}

}  // namespace acvo_ros
