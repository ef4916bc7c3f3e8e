// The point type of the published clouds: PCL's own layout (x y z + padding, packed rgb) with
// the five labels the registration uses, so that a PCL user reads a cloud back with
// pcl::fromROSMsg into pcl::PointCloud<acvo_ros::LabelledPoint> (every channel) or into any PCL
// type it contains (pcl::PointXYZRGB for colour, pcl::PointXYZ).
#pragma once

#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

// PCL's point macros declare anonymous structs inside unions (a GNU extension that GCC and
// clang accept); clang's pedantic diagnostics name them in PCL's own macros, not in this code.
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wgnu-anonymous-struct"
#pragma clang diagnostic ignored "-Wnested-anon-types"
#endif

namespace acvo_ros {

struct EIGEN_ALIGN16 LabelledPoint {
  PCL_ADD_POINT4D;  // x y z (optical frame, metres)
  PCL_ADD_RGB;      // the pixel's colour, packed as rviz and PCL read it
  float hue;         // H / 180 (OpenCV's 8-bit HSV)
  float saturation;  // S / 255
  float value;       // V / 255
  float gradient_x;  // 2 gx / 255, gx the central difference of the grey image along u
  float gradient_y;  // 2 gy / 255, along v
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};

}  // namespace acvo_ros

#if defined(__clang__)
#pragma clang diagnostic pop
#endif

POINT_CLOUD_REGISTER_POINT_STRUCT(acvo_ros::LabelledPoint,
                                  (float, x, x)(float, y, y)(float, z, z)(float, rgb, rgb)(
                                      float, hue, hue)(float, saturation, saturation)(
                                      float, value, value)(float, gradient_x, gradient_x)(
                                      float, gradient_y, gradient_y))
