// A camera whose turn rate keeps changing, sampled by a reference and by a camera on clocks of
// their own: what the clock-offset search (acvo::estimateClockOffset) is tested on.
#pragma once

#include <cmath>
#include <cstdio>
#include <random>

#include <Eigen/Geometry>

#include "acvo/dataset/tum.hpp"

namespace acvo::test {

// The pose at time t (s): turning about two axes at rates that change within a second (up to
// about 60 deg/s, a hand-held camera's), moving along a curve that no screw motion maps onto
// itself.
inline Eigen::Isometry3d wavingCamera(double t) {
  const double yaw = 0.5 * std::sin(2.0 * M_PI * 0.7 * t) + 0.2 * std::sin(2.0 * M_PI * 1.9 * t);
  const double pitch = 0.3 * std::sin(2.0 * M_PI * 1.1 * t + 0.4);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() =
      Eigen::Vector3d(0.5 * std::sin(1.3 * t), 0.1 * t, 0.3 * std::cos(0.4 * t));
  return pose;
}

// The camera sampled every 1 / rate s over [0, seconds], stamped 100 s + t, each pose the one
// at t + lag (a clock `lag` s behind the true one) turned by a random rotation of about
// noise_deg (a fixed seed).
inline Trajectory sampledCamera(double rate, double seconds, double lag, double noise_deg = 0.0,
                                unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, noise_deg * M_PI / 180.0 / std::sqrt(3.0));
  Trajectory out;
  for (int k = 0; k / rate <= seconds; ++k) {
    const double t = k / rate;
    Eigen::Isometry3d pose = wavingCamera(t + lag);
    if (noise_deg > 0.0) {
      const Eigen::Vector3d w(normal(rng), normal(rng), normal(rng));
      pose.linear() =
          pose.linear() * Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    }
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", 100.0 + t);
    out.push_back({text, 100.0 + t, pose});
  }
  return out;
}

}  // namespace acvo::test
