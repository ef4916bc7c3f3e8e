// Depth decoding into metres (TUM PNG, 16UC1 millimetres, 32FC1 metres); invalid depth as 0.
#include "acvo/cloud/depth.hpp"

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
      // Raw 0 and 65535 (no reading) give 0 and every other value a positive finite one: a product
      // by the inverse scale and a select for the mark, which the compiler vectorises (the division
      // per pixel of the generic path was a tenth of a frame's selection time).
      constexpr std::uint16_t none = DepthTraits<std::uint16_t>::kNoReading;
      for (int v = 0; v < raw.rows; ++v) {
        const std::uint16_t* in = raw.ptr<std::uint16_t>(v);
        float* o = out.ptr<float>(v);
        for (int u = 0; u < raw.cols; ++u) {
          o[u] = in[u] == none ? 0.0f : static_cast<float>(in[u] * inv);
        }
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
  // written out because that took 6 ms per 640x480 frame (teddy200, one thread, with the holes
  // turned to NaN and back), most of a frame's registration: here the ray of each column and
  // row is computed once, in float, and the projection is vectorised (0.6 ms).
  const Eigen::Isometry3f to_moved = moved.inverse().cast<float>();
  const Eigen::Matrix3f R = to_moved.linear();
  const Eigen::Vector3f t = to_moved.translation();
  const float fx = float(camera.fx), fy = float(camera.fy), cx = float(camera.cx),
              cy = float(camera.cy);
  const int cols = depth_m.cols, rows = depth_m.rows;
  std::vector<float> ray_x(std::size_t(cols), 0.0f);
  for (int u = 0; u < cols; ++u) ray_x[std::size_t(u)] = (float(u) - cx) / fx;
  // Per row, first where every pixel lands (a loop without stores elsewhere, which the compiler
  // vectorises), then the stores: -1 marks a pixel that lands nowhere.
  std::vector<int> target(std::size_t(cols), -1);
  std::vector<float> moved_z(std::size_t(cols), 0.0f);
  cv::Mat out(depth_m.size(), CV_32FC1, cv::Scalar(0.0f));
  auto* o = out.ptr<float>(0);
  const float u_max = float(cols) - 0.5f, v_max = float(rows) - 0.5f;
  const float r00 = R(0, 0), r10 = R(1, 0), r20 = R(2, 0), tx = t.x(), ty = t.y(), tz = t.z();
  for (int v = 0; v < rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    const float y = (float(v) - cy) / fy;
    const float r0 = R(0, 1) * y + R(0, 2), r1 = R(1, 1) * y + R(1, 2), r2 = R(2, 1) * y + R(2, 2);
    int* row_target = target.data();
    float* row_z = moved_z.data();
    for (int u = 0; u < cols; ++u) {
      const float z = in[u], x = ray_x[std::size_t(u)];
      const float px = (r00 * x + r0) * z + tx, py = (r10 * x + r1) * z + ty,
                  pz = (r20 * x + r2) * z + tz;
      const float inverse_z = 1.0f / pz;
      const float pu = fx * px * inverse_z + cx, pv = fy * py * inverse_z + cy;
      const bool lands = (z > 0.0f) & (pz > 0.0f) & (pu > -0.5f) & (pv > -0.5f) & (pu < u_max) &
                         (pv < v_max);
      // Rounded to the nearest pixel; a pixel that lands nowhere is converted from 0, never
      // from a value out of int's range.
      const int pixel = int(std::floor(lands ? pv + 0.5f : 0.0f)) * cols +
                        int(std::floor(lands ? pu + 0.5f : 0.0f));
      row_target[u] = lands ? pixel : -1;
      row_z[u] = pz;
    }
    for (int u = 0; u < cols; ++u) {
      const int k = row_target[u];
      if (k < 0) continue;
      if (o[k] == 0.0f || row_z[u] < o[k]) o[k] = row_z[u];  // the nearest surface hides the rest
    }
  }
  return out;
}

}  // namespace acvo
