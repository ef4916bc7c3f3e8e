// A frame's labelled cloud (docs/method.md §1): selected pixels back-projected, with their
// HSV and gradient labels and colours.
#include "acvo/cloud/labelled_cloud.hpp"

#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "acvo/cloud/hsv.hpp"
#include "acvo/timing.hpp"

namespace acvo {
namespace {

// R, G, B of one pixel whatever the frame's channel order (grey replicated).
std::array<std::uint8_t, 3> rgbAt(const Frame& frame, int u, int v) {
  if (frame.order == ColorOrder::kGray) {
    const std::uint8_t i = frame.color.at<std::uint8_t>(v, u);
    return {i, i, i};
  }
  const auto& c = frame.color.at<cv::Vec3b>(v, u);
  if (frame.order == ColorOrder::kRgb) return {c[0], c[1], c[2]};
  return {c[2], c[1], c[0]};
}

}  // namespace

LabelledCloud buildLabelledCloud(const Frame& frame, const SelectionParams& params,
                                 CloudStats* stats) {
  if (const std::string why = frame.problem(); !why.empty()) {
    throw std::invalid_argument("buildLabelledCloud: " + why);
  }
  // ms_selection counts the grey conversion too: it exists only for selection and gradients.
  const auto t0 = Clock::now();
  const cv::Mat gray = grayImage(frame);
  Selection selection = selectPixels(gray, frame.depth, params);
  const double ms_selection = msSince(t0);

  // HSV only at the kept pixels: converting the whole image would cost more than the rest.
  const auto t1 = Clock::now();
  LabelledCloud cloud;
  cloud.stamp = frame.stamp;
  cloud.depth_of_another_instant = frame.depth_stamp != 0.0 && frame.depth_stamp != frame.stamp;
  cloud.width = frame.color.cols;
  cloud.height = frame.color.rows;
  // The frame's images are the caller's: the cloud keeps its own copies.
  cloud.gray = frame.order == ColorOrder::kGray ? gray.clone() : gray;
  cloud.depth = frame.depth.clone();
  cloud.camera = frame.camera;
  cloud.pixels = std::move(selection.pixels);
  const std::size_t n = cloud.pixels.size();
  cloud.points.reserve(n);
  cloud.labels.reserve(n);
  cloud.rgb.reserve(n);
  const Camera& cam = frame.camera;
  for (const cv::Point& p : cloud.pixels) {
    const double z = frame.depth.at<float>(p.y, p.x);
    cloud.points.emplace_back(cam.backProject(p.x, p.y, z).cast<float>());

    const std::array<std::uint8_t, 3> rgb = rgbAt(frame, p.x, p.y);
    cloud.rgb.push_back(rgb);
    const std::array<std::uint8_t, 3> hsv = rgbToHsv(rgb[0], rgb[1], rgb[2]);
    // Selected pixels keep a 4-pixel border, so both neighbours exist.
    const auto* row = gray.ptr<std::uint8_t>(p.y);
    const float dx = static_cast<float>(row[p.x + 1]) - static_cast<float>(row[p.x - 1]);
    const float dy = static_cast<float>(gray.ptr<std::uint8_t>(p.y + 1)[p.x]) -
                     static_cast<float>(gray.ptr<std::uint8_t>(p.y - 1)[p.x]);
    Label label;
    // gx = dx / 2, normalised as gx / 255 * 2 = dx / 255.
    label << hsv[0] / 180.f, hsv[1] / 255.f, hsv[2] / 255.f, dx / 255.f, dy / 255.f;
    cloud.labels.push_back(label);
  }
  if (stats) {
    stats->selection = std::move(selection);
    stats->selection.pixels.clear();
    stats->ms_selection = ms_selection;
    stats->ms_labels = msSince(t1);
  }
  return cloud;
}

LabelledCloud withoutPoints(const LabelledCloud& cloud, std::size_t count) {
  LabelledCloud out;
  out.stamp = cloud.stamp;
  out.depth_of_another_instant = cloud.depth_of_another_instant;
  out.width = cloud.width;
  out.height = cloud.height;
  out.gray = cloud.gray;
  out.depth = cloud.depth;
  out.camera = cloud.camera;
  out.blur_motion = cloud.blur_motion;
  out.points.reserve(count);
  out.labels.reserve(count);
  out.pixels.reserve(count);
  out.rgb.reserve(count);
  return out;
}

LabelledCloud withDepth(const LabelledCloud& cloud, const cv::Mat& depth_m,
                        const SelectionParams& params) {
  if (depth_m.type() != CV_32FC1 || depth_m.cols != cloud.width || depth_m.rows != cloud.height) {
    throw std::invalid_argument("withDepth: expects CV_32FC1 metres of the cloud's image size");
  }
  LabelledCloud out = withoutPoints(cloud, cloud.size());
  out.depth = depth_m;
  const SelectableDepth selectable(params);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const cv::Point& p = cloud.pixels[i];
    const float z = depth_m.at<float>(p.y, p.x);
    if (!selectable(z)) continue;
    out.points.emplace_back(cloud.camera.backProject(p.x, p.y, z).cast<float>());
    out.labels.push_back(cloud.labels[i]);
    out.pixels.push_back(p);
    out.rgb.push_back(cloud.rgb[i]);
  }
  return out;
}

}  // namespace acvo
