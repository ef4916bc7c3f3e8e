// Pinhole intrinsics of the colour image, the depth scale, and back-projection.
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>

namespace acvo {

struct Camera {
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;
  int width = 640;
  int height = 480;
  // Raw depth units per metre: 5000 for TUM PNG, 1000 for 16UC1 millimetres, 1 for metres.
  double depth_scale = 5000.0;

  // Pixel (u, v) at depth z metres -> point in the optical frame (x right, y down, z forward).
  Eigen::Vector3d backProject(double u, double v, double z) const {
    return {(u - cx) * z / fx, (v - cy) * z / fy, z};
  }
  // Optical-frame point -> pixel coordinates (z must be positive).
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
  }
  // Non-zero focal lengths, positive size and depth scale, all finite. A negative focal length is
  // an image axis that runs against the optical frame's, mirrored (ICL-NUIM's published
  // intrinsics have fy -480: its renderer's y axis points up). Back-projection and projection
  // hold with the sign as given, and the motion is the camera's in the frame they define.
  bool valid() const;
  bool mirrored() const { return fx < 0 || fy < 0; }
};

// Named intrinsics of the TUM RGB-D benchmark: "fr1", "fr2", "fr3", "default"
// (default = 525, 525, 319.5, 239.5); all 640x480 with depth scale 5000.
// Throws std::invalid_argument for an unknown name.
Camera cameraByName(const std::string& name);

// A lens's radial-tangential distortion in OpenCV's order (ROS's plumb_bob): k1 k2 p1 p2 k3.
struct LensDistortion {
  std::array<double, 5> coefficients{};
  bool any() const;
};

// TUM's published distortion of its raw fr1 and fr2 colour images; zero for fr3 (its images
// were undistorted before publication) and default.
LensDistortion distortionByName(const std::string& name);

// Whether these are nominal intrinsics rather than a calibration of one camera: equal focal
// lengths, the principal point at the image's centre (w/2, (w-1)/2 or (w+1)/2 across, the
// conventions datasets, drivers and simulators use, and likewise down) and no lens distortion.
// Exact for a simulated camera; for a real one, a driver's or a dataset's defaults are a few
// percent off, which a registration of the depth's geometry carries in full (`acvo_compare
// --camera` measures a folder's sensitivity). A calibration never lands on all of these to the
// millionth of a pixel.
bool nominalIntrinsics(const Camera& camera, const LensDistortion& distortion);

// What a camera.yaml says: the pinhole intrinsics and the lens they were calibrated with.
struct CameraFile {
  Camera camera;
  LensDistortion distortion;
};

// Reads a camera.yaml once. Intrinsics: fx, fy, cx, cy (or, as camera_calibration and OpenCV
// write it, camera_matrix: a 3x3 matrix's 9 numbers, as a list or {data: [...]}), width and
// height (or image_width, image_height; both absent: 0 x 0, for the caller to take from the
// images), and depth_scale (optional, default 5000). Distortion: k1 k2 p1 p2 k3, or d0 d1 d2
// d3 d4 (TUM's names), or distortion_coefficients as a list or {data: [...]}; absent keys are
// 0, and each given one must be a finite number. Throws std::runtime_error naming the file and
// the problem.
CameraFile readCameraFile(const std::string& path);
// The intrinsics of readCameraFile.
Camera loadCameraYaml(const std::string& path);
void saveCameraYaml(const std::string& path, const Camera& camera);

}  // namespace acvo
