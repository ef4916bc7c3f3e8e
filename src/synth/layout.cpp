#include "synth/layout.hpp"

namespace acvo::synth {

Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();  // right = forward x up
  const Eigen::Vector3d y = z.cross(x);                // down completes a right-handed frame
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = x;
  pose.linear().col(1) = y;
  pose.linear().col(2) = z;
  pose.translation() = eye;
  return pose;
}

Eigen::Isometry3d defaultStartPose() {
  return lookAt(kStartEye, kLookAtTarget);
}

}  // namespace acvo::synth
