// Where things are in the synthetic world, shared by the scene and the trajectories.
//
// World frame: metres, z up, floor at z = 0. Distances are those of a handheld Kinect in an
// office (most of the view 1-3 m away, as in the TUM fr1 sequences). The room spans kRoomMin..kRoomMax; the camera
// starts near the back wall (negative y) and looks towards kLookAtTarget, a point above the
// floor in the middle of the room where the furniture stands. Camera poses are
// camera-to-world in the optical convention (x right, y down, z forward), as in TUM
// groundtruth files.
#pragma once

#include <Eigen/Geometry>

namespace acvo::synth {

inline const Eigen::Vector3d kRoomMin{-3.0, -2.5, 0.0};
inline const Eigen::Vector3d kRoomMax{3.0, 2.6, 2.7};
inline const Eigen::Vector3d kStartEye{0.0, -0.6, 1.3};
inline const Eigen::Vector3d kLookAtTarget{0.0, 1.2, 0.7};
inline const Eigen::Vector3d kWorldUp{0.0, 0.0, 1.0};

// Furniture stands in this floor region (x, y ranges), ahead of every camera position the
// trajectories reach, so the camera never ends up inside an object.
inline constexpr double kFurnitureMinY = 0.2;
inline constexpr double kFurnitureMaxY = 2.3;
inline constexpr double kFurnitureHalfWidthX = 2.6;

// With structure off the whole world is this one plane (y = kSinglePlaneY, facing the
// camera), through the look-at target: every view of every trajectory sees only it.
inline constexpr double kSinglePlaneY = 1.0;

// Camera-to-world pose of a camera at `eye` looking at `target`, image "up" towards `up`
// (optical frame: z along the view direction, x to the right, y down).
// `target - eye` must not be parallel to `up`.
Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up = kWorldUp);

// The start pose of every trajectory: kStartEye looking at kLookAtTarget (slightly
// downwards, into the furnished part of the room).
Eigen::Isometry3d defaultStartPose();

}  // namespace acvo::synth
