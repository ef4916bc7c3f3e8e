// Random twists for the SE(3) and window tests (test_se3, test_window).
#pragma once

#include <random>

#include "acvo/math/se3.hpp"

namespace acvo::test {

// A twist (omega, v) with normal entries of standard deviation `rot` (rad) and `trans` (m).
inline Vector6d randomTwist(std::mt19937& rng, double rot, double trans) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d xi;
  for (int k = 0; k < 3; ++k) xi[k] = rot * n(rng);
  for (int k = 3; k < 6; ++k) xi[k] = trans * n(rng);
  return xi;
}

}  // namespace acvo::test
