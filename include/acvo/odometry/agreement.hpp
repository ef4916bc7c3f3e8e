// How much of a frame a motion explains against its reference, pixel by pixel: a point agrees
// where it lands on a reference pixel of its own depth and grey level. The odometry asks this
// where no velocity is known yet, to tell the camera's motion from that of something large
// moving in view (docs/method.md §7, "the rest of the points").
#pragma once

#include <Eigen/Geometry>

#include "acvo/cloud/labelled_cloud.hpp"

namespace acvo {

// A point agrees with the reference under a motion when it lands on a reference pixel whose
// depth is within kAgreementDepth + kAgreementDepthQuadratic z^2 of its own (a Kinect's depth
// noise at 3 m is about 3 cm) and whose grey level is within kAgreementGrey of its own (about
// 3 standard deviations of a camera's grey noise: a surface moved sideways keeps its depth but
// not its texture).
inline constexpr double kAgreementDepth = 0.01;            // m
inline constexpr double kAgreementDepthQuadratic = 0.005;  // 1/m
inline constexpr int kAgreementGrey = 12;                  // grey levels
// Pixels between the samples of denseAgreement (4800 on a 640x480 image).
inline constexpr int kAgreementStride = 8;

// The points of `moving` that land on a reference pixel with depth under `to_reference`
// (moving -> reference) and disagree with it there; its images and camera are `moving`'s.
// Empty where either cloud has no images, or `moving` no pixel for each point.
LabelledCloud disagreeingPoints(const LabelledCloud& reference, const LabelledCloud& moving,
                                const Eigen::Isometry3d& to_reference);

// How many of `moving`'s pixels with depth, every kAgreementStride in each direction, agree with
// the reference under `to_reference`: the support of a motion over the whole image, whatever
// the selection chose (a near, textured object holds more selected points than pixels).
int denseAgreement(const LabelledCloud& reference, const LabelledCloud& moving,
                   const Eigen::Isometry3d& to_reference);

}  // namespace acvo
