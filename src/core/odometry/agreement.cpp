#include "acvo/odometry/agreement.hpp"

#include <cmath>
#include <cstdint>
#include <optional>

namespace acvo {
namespace {

bool hasImages(const LabelledCloud& cloud) {
  return cloud.depth.type() == CV_32FC1 && cloud.gray.type() == CV_8UC1 && !cloud.depth.empty() &&
         cloud.depth.size() == cloud.gray.size();
}

// Whether a point `y` of the reference's frame, of grey level `grey`, agrees with the reference
// image where it lands; none where it lands off the image or on no depth.
std::optional<bool> agreesWhereItLands(const LabelledCloud& reference, const Eigen::Vector3d& y,
                                       int grey) {
  if (!(y.z() > 0.0)) return std::nullopt;
  const Eigen::Vector2d pixel = reference.camera.project(y);
  const double u = std::round(pixel.x()), v = std::round(pixel.y());
  if (!(u >= 0.0 && v >= 0.0 && u < reference.depth.cols && v < reference.depth.rows)) {
    return std::nullopt;
  }
  const float z = reference.depth.at<float>(int(v), int(u));
  if (!(z > 0.0f) || !std::isfinite(z)) return std::nullopt;
  return std::abs(double(z) - y.z()) <
             kAgreementDepth + kAgreementDepthQuadratic * y.z() * y.z() &&
         std::abs(int(reference.gray.at<std::uint8_t>(int(v), int(u))) - grey) < kAgreementGrey;
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
    const std::optional<bool> agrees =
        agreesWhereItLands(reference, to_reference * moving.points[i].cast<double>(),
                           moving.gray.at<std::uint8_t>(p.y, p.x));
    if (!agrees || *agrees) continue;
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
      const std::optional<bool> agrees =
          agreesWhereItLands(reference, to_reference * moving.camera.backProject(u, v, z),
                             moving.gray.at<std::uint8_t>(v, u));
      if (agrees.value_or(false)) ++count;
    }
  }
  return count;
}

}  // namespace acvo
