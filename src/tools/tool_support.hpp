// Small helpers shared by the command-line tools (not part of the library's interface).
#pragma once

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "acvo/params.hpp"
#include "acvo/tum.hpp"

namespace acvo::tools {

// Linear interpolation between order statistics (q in [0, 1]); 0 for an empty list.
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * double(v.size() - 1);
  const std::size_t lo = std::size_t(std::floor(pos)), hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - double(lo)) * (v[hi] - v[lo]);
}

// Parameters from a YAML file (empty: the defaults), then each "SECTION.KEY=VALUE" of --set on
// top. Throws std::invalid_argument for a malformed --set, std::runtime_error (naming the key)
// for an unknown key or a bad value.
inline Params loadToolParams(const std::string& config, const std::vector<std::string>& sets) {
  Params p = config.empty() ? Params() : loadParams(config);
  for (const auto& s : sets) {
    const auto dot = s.find('.'), eq = s.find('=');
    if (dot == std::string::npos || eq == std::string::npos || eq < dot) {
      throw std::invalid_argument("--set expects SECTION.KEY=VALUE, got '" + s + "'");
    }
    const std::string yaml =
        s.substr(0, dot) + ":\n  " + s.substr(dot + 1, eq - dot - 1) + ": " + s.substr(eq + 1);
    p = parseParams(yaml, p, "--set " + s);
  }
  return p;
}

// The ground-truth pose nearest in time to `stamp` within 0.02 s (as TUM associates), if any.
inline const StampedPose* nearestPose(const Trajectory& gt, double stamp) {
  const StampedPose* best = nullptr;
  for (const auto& p : gt) {
    if (std::abs(p.stamp - stamp) < 0.02 &&
        (!best || std::abs(p.stamp - stamp) < std::abs(best->stamp - stamp))) {
      best = &p;
    }
  }
  return best;
}

// Resident set size of this process in KiB (VmRSS of /proc/self/status); -1 when unreadable.
inline long residentKiB() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      long kib = -1;
      status >> kib;
      return kib;
    }
    status.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return -1;
}

}  // namespace acvo::tools
