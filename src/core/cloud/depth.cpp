// Depth decoding into metres (TUM PNG, 16UC1 millimetres, 32FC1 metres); invalid depth as 0.
#include "acvo/depth.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace acvo {
namespace {

template <typename T>
void convert(const cv::Mat& raw, double units_per_metre, cv::Mat& out) {
  for (int v = 0; v < raw.rows; ++v) {
    const T* in = raw.ptr<T>(v);
    float* o = out.ptr<float>(v);
    for (int u = 0; u < raw.cols; ++u) {
      const float m = DepthTraits<T>::valid(in[u]) ? DepthTraits<T>::toMeters(in[u], units_per_metre)
                                                   : 0.0f;
      o[u] = (std::isfinite(m) && m > 0.0f) ? m : 0.0f;
    }
  }
}

}  // namespace

cv::Mat depthToMeters(const cv::Mat& raw, double units_per_metre) {
  if (!(units_per_metre > 0.0) || !std::isfinite(units_per_metre)) {
    throw std::invalid_argument("depth scale must be positive and finite");
  }
  cv::Mat out(raw.size(), CV_32FC1);
  switch (raw.type()) {
    case CV_16UC1: {
      const double inv = 1.0 / units_per_metre;
      if (!(65535.0 * inv <= std::numeric_limits<float>::max())) {
        convert<std::uint16_t>(raw, units_per_metre, out);  // some values beyond float
        break;
      }
      // Raw 0 (no depth) gives 0 and every other value a positive finite one: a product by the
      // inverse scale, without the branches, which the compiler vectorises (the division per
      // pixel of the generic path was a tenth of a frame's selection time).
      for (int v = 0; v < raw.rows; ++v) {
        const std::uint16_t* in = raw.ptr<std::uint16_t>(v);
        float* o = out.ptr<float>(v);
        for (int u = 0; u < raw.cols; ++u) o[u] = static_cast<float>(in[u] * inv);
      }
      break;
    }
    case CV_32FC1:
      convert<float>(raw, units_per_metre, out);
      break;
    default:
      throw std::invalid_argument("unsupported depth image type " + cv::typeToString(raw.type()) +
                                  " (expected 16UC1 or 32FC1)");
  }
  return out;
}

cv::Mat depthSeenFrom(const cv::Mat& depth_m, const Camera& camera,
                      const Eigen::Isometry3d& moved) {
  if (depth_m.type() != CV_32FC1 || depth_m.cols != camera.width || depth_m.rows != camera.height)
    throw std::invalid_argument("depthSeenFrom: expects CV_32FC1 metres of the camera's size");
  // The same forward projection as cv::rgbd::registerDepth (which also handles two cameras),
  // written out because that took 6 ms per 640x480 frame (teddy200, one thread), most of a
  // frame's registration: here the ray of each column and row is computed once, in float.
  const Eigen::Isometry3f to_moved = moved.inverse().cast<float>();
  const Eigen::Matrix3f R = to_moved.linear();
  const Eigen::Vector3f t = to_moved.translation();
  const float fx = float(camera.fx), fy = float(camera.fy), cx = float(camera.cx),
              cy = float(camera.cy);
  std::vector<float> ray_x(std::size_t(depth_m.cols));
  for (int u = 0; u < depth_m.cols; ++u) ray_x[std::size_t(u)] = (float(u) - cx) / fx;
  cv::Mat out(depth_m.size(), CV_32FC1, cv::Scalar(0.0f));
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    const Eigen::Vector3f row = R.col(1) * ((float(v) - cy) / fy) + R.col(2);
    for (int u = 0; u < depth_m.cols; ++u) {
      const float z = in[u];
      if (!(z > 0.0f)) continue;
      const Eigen::Vector3f p = (R.col(0) * ray_x[std::size_t(u)] + row) * z + t;
      if (!(p.z() > 0.0f)) continue;
      const float inverse_z = 1.0f / p.z();
      const float pu = fx * p.x() * inverse_z + cx, pv = fy * p.y() * inverse_z + cy;
      if (!(pu > -0.5f && pv > -0.5f && pu < float(depth_m.cols) - 0.5f &&
            pv < float(depth_m.rows) - 0.5f))
        continue;
      float& o = out.at<float>(cvRound(pv), cvRound(pu));  // the nearest pixel
      if (o == 0.0f || p.z() < o) o = p.z();  // the nearest surface hides the others
    }
  }
  return out;
}

}  // namespace acvo
