// Is the depth registered to the colour? (acvo/colour_depth_check.hpp)
#include "acvo/colour_depth_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace acvo {
namespace {

constexpr int kBorder = 3;  // edges this close to the image border are left out

bool inside(const cv::Mat& image, double x, double y) {
  return x >= 0.0 && y >= 0.0 && x <= image.cols - 1.0 && y <= image.rows - 1.0;
}

// Bilinear sample of a CV_32FC1 image at a point inside it.
float sample(const cv::Mat& image, double x, double y) {
  const int x0 = std::min(int(x), image.cols - 2), y0 = std::min(int(y), image.rows - 2);
  const float fx = float(x - x0), fy = float(y - y0);
  const float* r0 = image.ptr<float>(y0);
  const float* r1 = image.ptr<float>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) +
         fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

}  // namespace

ColourDepthCheck::ColourDepthCheck(const Options& options) : options_(options) {}

std::vector<std::array<int, 2>> ColourDepthCheck::depthEdges(const cv::Mat& depth,
                                                             double depth_jump) {
  std::vector<std::array<int, 2>> edges;
  if (depth.rows <= 2 * kBorder || depth.cols <= 2 * kBorder) return edges;
  // The farthest depth within 3 px: a Kinect leaves a pixel or two without depth on either
  // side of a jump, so the nearest neighbours alone would miss most silhouettes.
  cv::Mat farthest;
  cv::dilate(depth, farthest, cv::Mat::ones(7, 7, CV_8U));
  for (int v = kBorder; v < depth.rows - kBorder; ++v) {
    const float* d = depth.ptr<float>(v);
    const float* f = farthest.ptr<float>(v);
    for (int u = kBorder; u < depth.cols - kBorder; ++u) {
      if (d[u] > 0.0f && std::isfinite(d[u]) && f[u] - d[u] > depth_jump * d[u]) {
        edges.push_back({u, v});
      }
    }
  }
  return edges;
}

std::array<double, ColourDepthCheck::kRatios> ColourDepthCheck::scores(
    const cv::Mat& grey, const Camera& camera, const std::vector<std::array<int, 2>>& edges) {
  std::array<double, kRatios> out{};
  if (edges.empty() || grey.cols < 2 || grey.rows < 2) return out;
  cv::Mat gx, gy, magnitude;
  cv::Sobel(grey, gx, CV_32F, 1, 0, 3);
  cv::Sobel(grey, gy, CV_32F, 0, 1, 3);
  cv::magnitude(gx, gy, magnitude);
  cv::GaussianBlur(magnitude, magnitude, cv::Size(), 1.0);
  const double mean = cv::mean(magnitude)[0];
  if (!(mean > 0.0)) return out;  // a blank image: no colour edges anywhere
  for (int i = 0; i < kRatios; ++i) {
    const double ratio = ratioAt(i);
    double sum = 0.0;
    int n = 0;
    for (const auto& [u, v] : edges) {
      const double x = camera.cx + ratio * (u - camera.cx), y = camera.cy + ratio * (v - camera.cy);
      if (!inside(magnitude, x, y)) continue;  // a narrower colour camera does not see it
      sum += sample(magnitude, x, y);
      ++n;
    }
    out[std::size_t(i)] = n > 0 ? sum / (mean * double(n)) : 0.0;
  }
  return out;
}

const ColourDepthCheck::Verdict& ColourDepthCheck::add(const Frame& frame) {
  if (decided() || !frame.problem().empty()) return verdict_;
  ++verdict_.frames_seen;
  const auto edges = depthEdges(frame.depth, options_.depth_jump);
  if (int(edges.size()) < options_.min_edge_pixels) return verdict_;
  const auto s = scores(grayImage(frame), frame.camera, edges);
  if (s[kRatios / 2] <= 0.0) return verdict_;  // no colour edges (a blank colour image)
  for (int i = 0; i < kRatios; ++i) sum_[std::size_t(i)] += s[std::size_t(i)];
  frame_best_.push_back(int(std::max_element(s.begin(), s.end()) - s.begin()));
  ++verdict_.frames;
  if (verdict_.frames >= options_.frames_needed) decide();
  return verdict_;
}

void ColourDepthCheck::decide() {
  const int best = int(std::max_element(sum_.begin(), sum_.end()) - sum_.begin());
  const int one = kRatios / 2;  // ratio 1.00
  verdict_.best_ratio = ratioAt(best);
  verdict_.gain = sum_[std::size_t(best)] / sum_[std::size_t(one)];
  // Options in ratios, as whole steps of the ratio grid.
  auto steps = [](double ratio) { return int(std::lround(ratio / kRatioStep)); };
  const int within = steps(options_.agreement_within);
  const int near = int(std::count_if(frame_best_.begin(), frame_best_.end(),
                                     [&](int b) { return std::abs(b - best) <= within; }));
  verdict_.agreement = double(near) / double(frame_best_.size());
  const bool unregistered = std::abs(best - one) >= steps(options_.min_offset) &&
                            verdict_.gain >= options_.min_gain &&
                            verdict_.agreement >= options_.min_agreement;
  verdict_.state = unregistered ? State::kUnregistered : State::kRegistered;
}

std::string ColourDepthCheck::describe() const {
  const Verdict& v = verdict_;
  char text[512];
  switch (v.state) {
    case State::kUndecided:
      std::snprintf(text, sizeof text,
                    "colour/depth registration undecided: %d of %d frames had enough depth edges",
                    v.frames, v.frames_seen);
      break;
    case State::kRegistered:
      std::snprintf(text, sizeof text,
                    "colour/depth registration: the colour edges lie on the depth edges (best "
                    "focal ratio %.2f, %.2fx ratio 1's score, %d frames)",
                    v.best_ratio, v.gain, v.frames);
      break;
    case State::kUnregistered:
      std::snprintf(text, sizeof text,
                    "the depth image does not look registered to the colour image: the colour "
                    "edges fit the depth edges best with the colour focal length %.2f times the "
                    "depth's (%.1fx the score as given, %d frames). acvo needs depth registered "
                    "pixel for pixel to the colour camera: use the driver's depth_registered "
                    "image (openni2_launch depth_registration:=true, realsense2_camera "
                    "align_depth:=true) or depth_image_proc/register",
                    v.best_ratio, v.gain, v.frames);
      break;
  }
  return text;
}

std::string toString(ColourDepthCheck::State state) {
  switch (state) {
    case ColourDepthCheck::State::kRegistered:
      return "registered";
    case ColourDepthCheck::State::kUnregistered:
      return "unregistered";
    case ColourDepthCheck::State::kUndecided:
      break;
  }
  return "undecided";
}

Frame withColourResampled(const Frame& frame, double ratio) {
  if (frame.color.empty() || ratio == 1.0 || !(ratio > 0.0)) return frame;
  const Camera& c = frame.camera;
  // Scaling about the principal point: cv::warpAffine with the map from each output pixel to
  // where it is read.
  const cv::Matx23d to_colour(ratio, 0.0, c.cx * (1.0 - ratio), 0.0, ratio, c.cy * (1.0 - ratio));
  Frame out = frame;
  out.color = cv::Mat();  // a new image: the frame's own is shared, not written
  cv::warpAffine(frame.color, out.color, to_colour, frame.color.size(),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  if (ratio > 1.0 && !frame.depth.empty()) {
    // The colour image's reach is a rectangle: the columns and rows it covers, once each.
    const cv::Mat& colour = frame.color;
    std::vector<bool> seen_u(std::size_t(frame.depth.cols));
    for (int u = 0; u < frame.depth.cols; ++u) {
      seen_u[std::size_t(u)] = inside(colour, c.cx + ratio * (u - c.cx), 0.0);
    }
    out.depth = frame.depth.clone();
    for (int v = 0; v < out.depth.rows; ++v) {
      const bool seen_v = inside(colour, 0.0, c.cy + ratio * (v - c.cy));
      auto* d = out.depth.ptr<float>(v);
      for (int u = 0; u < out.depth.cols; ++u) {
        if (!seen_v || !seen_u[std::size_t(u)]) d[u] = 0.0f;
      }
    }
  }
  return out;
}

}  // namespace acvo
