// SE(3) exponential and logarithm in closed form, with small-angle series.
#include "acvo/math/se3.hpp"

#include <cmath>

namespace acvo {
namespace {

// Coefficients A = sin(t)/t, B = (1 - cos t)/t^2, C = (t - sin t)/t^3 with series below
// a small angle, where the closed forms lose precision to cancellation.
struct RodriguesCoefficients {
  double A, B, C;
};

RodriguesCoefficients coefficients(double theta) {
  const double t2 = theta * theta;
  if (theta < 0.1) {
    // Series to theta^8: truncation below 1e-16 relative for theta < 0.1.
    const double t4 = t2 * t2, t6 = t4 * t2, t8 = t4 * t4;
    return {1.0 - t2 / 6.0 + t4 / 120.0 - t6 / 5040.0 + t8 / 362880.0,
            0.5 - t2 / 24.0 + t4 / 720.0 - t6 / 40320.0 + t8 / 3628800.0,
            1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0 - t6 / 362880.0 + t8 / 39916800.0};
  }
  const double s = std::sin(theta), c = std::cos(theta);
  return {s / theta, (1.0 - c) / t2, (theta - s) / (t2 * theta)};
}

// D of SO(3)'s V^-1 = I - W/2 + D W^2 (also its left Jacobian's inverse), series below 0.1.
double inverseCoefficient(double theta) {
  if (theta < 0.1) {
    const double t2 = theta * theta;
    return 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0 + t2 * t2 * t2 / 1209600.0;
  }
  const auto k = coefficients(theta);
  return (1.0 - k.A / (2.0 * k.B)) / (theta * theta);
}

}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return W;
}

Matrix6d adjointSE3(const Eigen::Isometry3d& T) {
  Matrix6d ad = Matrix6d::Zero();
  ad.topLeftCorner<3, 3>() = T.linear();
  ad.bottomRightCorner<3, 3>() = T.linear();
  ad.bottomLeftCorner<3, 3>() = hat(T.translation()) * T.linear();
  return ad;
}

Eigen::Matrix3d expSO3(const Eigen::Vector3d& w) {
  const auto k = coefficients(w.norm());
  const Eigen::Matrix3d W = hat(w);
  return Eigen::Matrix3d::Identity() + k.A * W + k.B * W * W;
}

Eigen::Vector3d logSO3(const Eigen::Matrix3d& R) {
  // Through the unit quaternion: atan2 keeps full precision at both ends of [0, pi].
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double n = q.vec().norm();
  const double w = q.w();
  double scale;
  if (n < 1e-8) {
    // theta = 2 atan(n / w) ~ 2 n / w (1 - n^2 / (3 w^2))
    scale = 2.0 / w * (1.0 - n * n / (3.0 * w * w));
  } else {
    scale = 2.0 * std::atan2(n, w) / n;
  }
  return scale * q.vec();
}

Eigen::Isometry3d expSE3(const Vector6d& xi) {
  const Eigen::Vector3d w = xi.head<3>(), v = xi.tail<3>();
  const auto k = coefficients(w.norm());
  const Eigen::Matrix3d W = hat(w), W2 = W * W;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Matrix3d::Identity() + k.A * W + k.B * W2;
  // V = I + B W + C W^2; for omega = 0 this is the identity and t = v exactly.
  T.translation() = v + k.B * (W * v) + k.C * (W2 * v);
  return T;
}

Vector6d logSE3(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d w = logSO3(T.linear());
  const double theta = w.norm();
  const Eigen::Matrix3d W = hat(w);
  // V^-1 = I - W/2 + D W^2 with D = (1 - A / (2B)) / theta^2.
  const double D = inverseCoefficient(theta);
  const Eigen::Vector3d v =
      T.translation() - 0.5 * (W * T.translation()) + D * (W * (W * T.translation()));
  // Two assignments, not `xi << w, v`: GCC 12 warns (-Warray-bounds, a false positive) about
  // the 4-double load Eigen's comma initializer makes from the 3-vector w under AVX.
  Vector6d xi;
  xi.head<3>() = w;
  xi.tail<3>() = v;
  return xi;
}

Matrix6d leftJacobianInverseSE3(const Vector6d& xi) {
  const Eigen::Vector3d w = xi.head<3>();
  const double theta = w.norm(), t2 = theta * theta;
  const Eigen::Matrix3d P = hat(w), R = hat(xi.tail<3>());
  const Eigen::Matrix3d J_inv =
      Eigen::Matrix3d::Identity() - 0.5 * P + inverseCoefficient(theta) * P * P;
  // Q's coefficients (theta - sin)/theta^3, (theta^2 + 2 cos - 2)/(2 theta^4) and
  // (2 theta - 3 sin + theta cos)/(2 theta^5), as series below 0.1 where they cancel.
  double c1, c2, c3;
  if (theta < 0.1) {
    c1 = coefficients(theta).C;
    c2 = 1.0 / 24.0 - t2 / 720.0 + t2 * t2 / 40320.0;
    c3 = 1.0 / 120.0 - t2 / 2520.0 + t2 * t2 / 120960.0;
  } else {
    const double s = std::sin(theta), c = std::cos(theta);
    c1 = (theta - s) / (t2 * theta);
    c2 = (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2);
    c3 = (2.0 * theta - 3.0 * s + theta * c) / (2.0 * t2 * t2 * theta);
  }
  const Eigen::Matrix3d PR = P * R, RP = R * P, PRP = PR * P;
  const Eigen::Matrix3d Q = 0.5 * R + c1 * (PR + RP + PRP) + c2 * (P * PR + RP * P - 3.0 * PRP) +
                            c3 * (PRP * P + P * PRP);
  Matrix6d out = Matrix6d::Zero();
  out.topLeftCorner<3, 3>() = J_inv;
  out.bottomRightCorner<3, 3>() = J_inv;
  out.bottomLeftCorner<3, 3>() = -J_inv * Q * J_inv;
  return out;
}

Eigen::Isometry3d normalized(const Eigen::Isometry3d& T) {
  Eigen::Isometry3d out = T;
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  return out;
}

}  // namespace acvo
