// The pieces of one iteration of the paper's engine (docs/method.md §3-§4): the step size, the
// search direction, the length-scale update, the stall rule and CVO's schedule.
#include <algorithm>
#include <cmath>
#include <string>

#include "acvo/registration/paper.hpp"

namespace acvo {
namespace {

// Smallest positive root of a t + b = 0 / a t^2 + b t + c = 0 (none: +inf).
double smallestPositiveLinear(double a, double b) {
  if (a == 0.0) return INFINITY;
  const double t = -b / a;
  return t > 0.0 ? t : INFINITY;
}

double smallestPositiveQuadratic(double a, double b, double c) {
  const double scale = std::max({std::abs(a), std::abs(b), std::abs(c)});
  if (scale == 0.0) return INFINITY;
  if (std::abs(a) <= 1e-14 * scale) return smallestPositiveLinear(b, c);
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return INFINITY;
  // Numerically stable pair of roots.
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  double best = INFINITY;
  for (double t : {q / a, q != 0.0 ? c / q : INFINITY}) {
    if (t > 0.0 && std::isfinite(t)) best = std::min(best, t);
  }
  return best;
}

// Real roots of t^3 + a t^2 + b t + c (trigonometric / Cardano), polished by Newton steps.
double smallestPositiveCubic(double A3, double A2, double A1, double A0) {
  const double scale = std::max({std::abs(A3), std::abs(A2), std::abs(A1), std::abs(A0)});
  if (scale == 0.0) return INFINITY;
  if (std::abs(A3) <= 1e-14 * scale) return smallestPositiveQuadratic(A2, A1, A0);
  const double a = A2 / A3, b = A1 / A3, c = A0 / A3;
  const double Q = (a * a - 3.0 * b) / 9.0;
  const double R = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
  double roots[3];
  int count = 0;
  if (R * R < Q * Q * Q) {
    const double theta = std::acos(std::clamp(R / std::sqrt(Q * Q * Q), -1.0, 1.0));
    const double m = -2.0 * std::sqrt(Q);
    roots[0] = m * std::cos(theta / 3.0) - a / 3.0;
    roots[1] = m * std::cos((theta + 2.0 * M_PI) / 3.0) - a / 3.0;
    roots[2] = m * std::cos((theta - 2.0 * M_PI) / 3.0) - a / 3.0;
    count = 3;
  } else {
    const double Aa = -std::copysign(std::cbrt(std::abs(R) + std::sqrt(R * R - Q * Q * Q)), R);
    const double Bb = Aa != 0.0 ? Q / Aa : 0.0;
    roots[0] = Aa + Bb - a / 3.0;
    count = 1;
  }
  double best = INFINITY;
  for (int k = 0; k < count; ++k) {
    double t = roots[k];
    for (int it = 0; it < 3; ++it) {  // polish
      const double f = ((t + a) * t + b) * t + c;
      const double df = (3.0 * t + 2.0 * a) * t + b;
      if (df == 0.0) break;
      t -= f / df;
    }
    if (t > 0.0 && std::isfinite(t)) best = std::min(best, t);
  }
  return best;
}

}  // namespace

double solveStep(double B, double C, double D, double E, double min_step, double max_step) {
  double t = smallestPositiveCubic(4.0 * E, 3.0 * D, 2.0 * C, B);
  if (!std::isfinite(t)) t = min_step;
  return std::min(t, max_step);
}

bool LengthScale::pinned(const PaperParams& p) const {
  return ell <= p.ell_min || ell >= ell_max;
}

double lengthScaleGradient(const SelfSums& xx, const SelfSums& yy, const CrossSums& xy, double ell,
                           EllUpdate update) {
  double grad = (xx.sum_d2 + yy.sum_d2 - 2.0 * xy.F_d2) / (ell * ell * ell);
  // Normalised by the kernel entries of the three matrices, every row counted, as the authors'
  // code does (it leaves rows out of the Ayy sum above, not out of this count).
  const double denom = double(xx.nnz_all + yy.nnz_all - 2 * xy.nnz);
  if (update == EllUpdate::kReference ? denom != 0.0 : denom > 0.0) grad /= denom;
  return grad;
}

bool updateLengthScale(LengthScale& ls, double gradient, const PaperParams& p) {
  if (!std::isfinite(gradient)) return false;
  ls.ell = p.ell_update == EllUpdate::kReference ? ls.ell + p.ell_step * gradient
                                                 : ls.ell - p.ell_step * gradient;
  if (ls.ell >= ls.ell_max) {
    // ell_max never drops below ell_min: past that the bound would shrink forever.
    ls.ell_max = std::max(ls.ell_max * p.ell_reduction, p.ell_min);
    ++ls.reductions;
    ls.ell = ls.ell_max;
  }
  ls.ell = std::max(ls.ell, p.ell_min);
  return ls.pinned(p);
}

double scheduledEll(int iteration) {
  // The authors' code switches at the end of iterations 3, 10 and 20 (k > 2, k > 9, k > 19).
  if (iteration < 4) return 0.15;
  if (iteration < 11) return 0.10;
  if (iteration < 21) return 0.06;
  return 0.03;
}

}  // namespace acvo
