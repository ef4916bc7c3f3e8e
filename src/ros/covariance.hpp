// Covariances in ROS messages. The model lives in the core (acvo/odometry/covariance.hpp: the
// pose covariance is the keyframe's plus the registration's to it, grown while lost); here only
// the order of the blocks differs: the engine puts rotation first, geometry_msgs puts x y z first.
#pragma once

#include <array>

#include <Eigen/Core>

#include "acvo/odometry/covariance.hpp"

namespace acvo_ros {

using Covariance6 = acvo::Matrix6d;
using acvo::kLostVariance;
using acvo::kOriginVariance;
using acvo::lostCovariance;
using acvo::originCovariance;

// Engine order (rotation x y z, translation x y z) -> ROS order (x y z, roll pitch yaw).
Covariance6 toRosOrder(const Covariance6& rotation_first);

// Row-major copy for the 36-element arrays of geometry_msgs.
std::array<double, 36> toArray(const Covariance6& c);

}  // namespace acvo_ros
