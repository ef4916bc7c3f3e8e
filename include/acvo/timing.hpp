// Milliseconds of wall time since a point of the steady clock: what every stage's time in
// OdometryResult and SolverResult is measured with.
#pragma once

#include <chrono>

namespace acvo {

using Clock = std::chrono::steady_clock;

inline double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace acvo
