#include "acvo/agreement.hpp"

#include <cmath>
#include <cstdint>

namespace acvo {
namespace {

bool hasImages(const LabelledCloud& cloud) {
  return cloud.depth.type() == CV_32FC1 && cloud.gray.type() == CV_8UC1 && !cloud.depth.empty() &&
         cloud.depth.size() == cloud.gray.size();
}

// Whether a point `y` of the reference's frame, of grey level `grey`, agrees with the reference
// image where it lands; false where it lands off the image or on no depth.
bool landsOn(const LabelledCloud& reference, const Eigen::Vector3d& y, int grey, bool& agrees) {
  if (!(y.z() > 0.0)) return false;
  const Camera& c = reference.camera;
  const double u = std::round(c.fx * y.x() / y.z() + c.cx);
  const double v = std::round(c.fy * y.y() / y.z() + c.cy);
  if (!(u >= 0.0 && v >= 0.0 && u < reference.depth.cols && v < reference.depth.rows)) {
    return false;
  }
  const float z = reference.depth.at<float>(int(v), int(u));
  if (!(z > 0.0f) || !std::isfinite(z)) return false;
  agrees = std::abs(double(z) - y.z()) <
               kAgreementDepth + kAgreementDepthQuadratic * y.z() * y.z() &&
           std::abs(int(reference.gray.at<std::uint8_t>(int(v), int(u))) - grey) < kAgreementGrey;
  return true;
}

}  // namespace

LabelledCloud disagreeingPoints(const LabelledCloud& reference, const LabelledCloud& moving,
                                const Eigen::Isometry3d& to_reference) {
  LabelledCloud out = withoutPoints(moving, 0);
  // A cloud made of points alone has no pixels to read its grey levels at.
  const std::size_t n = moving.size();
  if (!hasImages(reference) || !hasImages(moving) || moving.pixels.size() != n ||
      moving.labels.size() != n || moving.rgb.size() != n) {
    return out;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const cv::Point& p = moving.pixels[i];
    bool agrees = false;
    if (!landsOn(reference, to_reference * moving.points[i].cast<double>(),
                 moving.gray.at<std::uint8_t>(p.y, p.x), agrees) ||
        agrees) {
      continue;
    }
    out.points.push_back(moving.points[i]);
    out.labels.push_back(moving.labels[i]);
    out.pixels.push_back(p);
    out.rgb.push_back(moving.rgb[i]);
  }
  return out;
}

int denseAgreement(const LabelledCloud& reference, const LabelledCloud& moving,
                   const Eigen::Isometry3d& to_reference) {
  if (!hasImages(reference) || !hasImages(moving)) return 0;
  int count = 0;
  constexpr int s = kAgreementStride;
  for (int v = s / 2; v < moving.depth.rows; v += s) {
    for (int u = s / 2; u < moving.depth.cols; u += s) {
      const float z = moving.depth.at<float>(v, u);
      if (!(z > 0.0f) || !std::isfinite(z)) continue;
      bool agrees = false;
      if (landsOn(reference, to_reference * moving.camera.backProject(u, v, z),
                  moving.gray.at<std::uint8_t>(v, u), agrees) &&
          agrees) {
        ++count;
      }
    }
  }
  return count;
}

}  // namespace acvo
