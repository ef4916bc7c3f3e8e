// Is the depth registered to the colour? (acvo/colour_depth_check.hpp)
#include "acvo/cloud/colour_depth_check.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
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

using EdgePoint = ColourDepthCheck::EdgePoint;

// The depth-edge pixels (u, v) with their depth.
std::vector<EdgePoint> edgePoints(const std::vector<std::array<int, 2>>& pixels,
                                  const cv::Mat& depth) {
  std::vector<EdgePoint> edges;
  edges.reserve(pixels.size());
  for (const auto& [u, v] : pixels) edges.push_back({float(u), float(v), depth.at<float>(v, u)});
  return edges;
}

// The grid's evidence: the edges thinned to every k-th (k = edges / max_edges, rounded down:
// under twice that many, all).
std::vector<EdgePoint> thinnedEdges(const std::vector<EdgePoint>& edges, int max_edges) {
  const std::size_t step =
      std::max<std::size_t>(1, edges.size() / std::size_t(std::max(1, max_edges)));
  std::vector<EdgePoint> thinned;
  for (std::size_t i = 0; i < edges.size(); i += step) thinned.push_back(edges[i]);
  return thinned;
}

}  // namespace

ColourDepthCheck::ColourDepthCheck(const Options& options) : options_(options) {
  camera_sum_.assign(cameraIndex(kRatios, 0), 0.0);
  for (auto& q : quarter_sum_) q.assign(camera_sum_.size(), 0.0);
}

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

cv::Mat ColourDepthCheck::edgeStrength(const cv::Mat& grey) {
  if (grey.cols < 2 || grey.rows < 2) return {};
  cv::Mat gx, gy, magnitude;
  cv::Sobel(grey, gx, CV_32F, 1, 0, 3);
  cv::Sobel(grey, gy, CV_32F, 0, 1, 3);
  cv::magnitude(gx, gy, magnitude);
  cv::GaussianBlur(magnitude, magnitude, cv::Size(), 1.0);
  const double mean = cv::mean(magnitude)[0];
  if (!(mean > 0.0)) return {};  // a blank image: no colour edges anywhere
  magnitude *= 1.0 / mean;
  return magnitude;
}

std::array<double, ColourDepthCheck::kRatios> ColourDepthCheck::scores(
    const cv::Mat& grey, const Camera& camera, const std::vector<std::array<int, 2>>& edges) {
  std::vector<EdgePoint> points;
  points.reserve(edges.size());
  for (const auto& [u, v] : edges) points.push_back({float(u), float(v), 1.0f});  // z: no baseline
  return ratioScores(edgeStrength(grey), camera, points);
}

std::array<double, ColourDepthCheck::kRatios> ColourDepthCheck::ratioScores(
    const cv::Mat& strength, const Camera& camera, const std::vector<EdgePoint>& edges) {
  std::array<double, kRatios> out{};
  if (edges.empty() || strength.empty()) return out;
  // A narrower colour camera does not see every edge: score() counts the ones it sees.
  for (int i = 0; i < kRatios; ++i) {
    out[std::size_t(i)] = score(strength, camera, edges, ratioAt(i), 0.0);
  }
  return out;
}

int ColourDepthCheck::quarterOf(const Camera& camera, const EdgePoint& e) {
  return (e.u > camera.cx ? 1 : 0) + (e.v > camera.cy ? 2 : 0);
}

ColourDepthCheck::Quarters ColourDepthCheck::quarterScores(const cv::Mat& strength,
                                                           const Camera& camera,
                                                           const std::vector<EdgePoint>& edges,
                                                           double ratio, double baseline) {
  const double shift = ratio * camera.fx * baseline;
  Quarters q;
  for (const EdgePoint& e : edges) {
    const double x = camera.cx + ratio * (e.u - camera.cx) - shift / e.z;
    const double y = camera.cy + ratio * (e.v - camera.cy);
    if (!inside(strength, x, y)) continue;
    const auto k = std::size_t(quarterOf(camera, e));
    q.sum[k] += sample(strength, x, y);
    ++q.n[k];
  }
  return q;
}

double ColourDepthCheck::score(const cv::Mat& strength, const Camera& camera,
                               const std::vector<EdgePoint>& edges, double ratio, double baseline) {
  const Quarters q = quarterScores(strength, camera, edges, ratio, baseline);
  const int n = q.n[0] + q.n[1] + q.n[2] + q.n[3];
  return n > 0 ? (q.sum[0] + q.sum[1] + q.sum[2] + q.sum[3]) / double(n) : 0.0;
}

const ColourDepthCheck::Verdict& ColourDepthCheck::add(const Frame& frame) {
  if (decided() || !frame.problem().empty()) return verdict_;
  ++verdict_.frames_seen;
  const auto pixels = depthEdges(frame.depth, options_.depth_jump);
  if (int(pixels.size()) < options_.min_edge_pixels) return verdict_;
  const std::vector<EdgePoint> edges = edgePoints(pixels, frame.depth);
  const cv::Mat strength = edgeStrength(grayImage(frame));
  const auto s = ratioScores(strength, frame.camera, edges);
  if (s[kRatios / 2] <= 0.0) return verdict_;  // no colour edges (a blank colour image)
  const std::vector<EdgePoint> thinned = thinnedEdges(edges, options_.max_edges_per_frame);
  // Every camera of the grid on those edges (41 x 13 cameras), in all and by the image's quarters
  // about the principal point. A quarter whose edges a camera does not see at all adds nothing
  // for it, which errs towards "registered".
  const int nb = baselines();
  std::vector<double> cameras(camera_sum_.size(), 0.0);
  std::array<std::vector<double>, 4> quarters;
  for (auto& q : quarters) q.assign(camera_sum_.size(), 0.0);
  int frame_best = 0;
  double frame_best_score = -1.0;
  for (int i = 0; i < kRatios; ++i) {
    for (int j = 0; j < nb; ++j) {
      const Quarters q =
          quarterScores(strength, frame.camera, thinned, ratioAt(i), baselineAt(j));
      double sum = 0.0;
      int n = 0;
      for (std::size_t k = 0; k < 4; ++k) {
        sum += q.sum[k];
        n += q.n[k];
        if (q.n[k] > 0) quarters[k][cameraIndex(i, j)] = q.sum[k] / q.n[k];
      }
      const double c = n > 0 ? sum / n : 0.0;
      cameras[cameraIndex(i, j)] = c;
      if (c > frame_best_score) {
        frame_best_score = c;
        frame_best = i;
      }
    }
  }
  // The thinned edges may all lie where the colour is flat: such a frame says nothing.
  if (!(cameras[cameraIndex(kRatios / 2, nb / 2)] > 0.0)) return verdict_;
  for (int i = 0; i < kRatios; ++i) sum_[std::size_t(i)] += s[std::size_t(i)];
  ++verdict_.frames;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    camera_sum_[c] += cameras[c];
    for (std::size_t k = 0; k < 4; ++k) quarter_sum_[k][c] += quarters[k][c];
  }
  for (const EdgePoint& e : thinned) {
    ++quarter_edges_[std::size_t(quarterOf(frame.camera, e))];
  }
  frame_camera_best_.push_back(frame_best);
  if (verdict_.frames >= options_.early_frames) decide(verdict_.frames >= options_.frames_needed);
  return verdict_;
}

bool ColourDepthCheck::atGridEnd(int i) { return i < kGridEnd || i >= kRatios - kGridEnd; }

int ColourDepthCheck::baselines() const {
  // Centres by kBaselineStep within max_baseline (none beyond it; just 0 for a negative or NaN).
  const double steps = std::floor(options_.max_baseline / kBaselineStep + 1e-9);
  return 2 * (steps > 0.0 ? int(std::min(steps, 100.0)) : 0) + 1;
}

double ColourDepthCheck::baselineAt(int j) const {
  const int centre = baselines() / 2;
  return double(j - centre) * kBaselineStep;
}

std::size_t ColourDepthCheck::cameraIndex(int i, int j) const {
  return std::size_t(i) * std::size_t(baselines()) + std::size_t(j);
}

void ColourDepthCheck::decide(bool final) {
  const int one = kRatios / 2;  // ratio 1.00
  // Options in ratios, as whole steps of the ratio grid.
  auto steps = [](double ratio) { return int(std::lround(ratio / kRatioStep)); };
  const int within = steps(options_.agreement_within), offset = steps(options_.min_offset);
  // The colour camera of the grid that fits best, against a camera in the depth camera's place.
  const int nb = baselines();
  const std::size_t at_one = cameraIndex(one, nb / 2);
  const auto best_camera = std::size_t(
      std::max_element(camera_sum_.begin(), camera_sum_.end()) - camera_sum_.begin());
  const int best = int(best_camera) / nb;
  verdict_.grid_ratio = ratioAt(best);
  verdict_.grid_baseline = baselineAt(int(best_camera) % nb);
  verdict_.gain = camera_sum_[at_one] > 0.0 ? camera_sum_[best_camera] / camera_sum_[at_one] : 1.0;
  const int near = int(std::count_if(frame_camera_best_.begin(), frame_camera_best_.end(),
                                     [&](int b) { return std::abs(b - best) <= within; }));
  verdict_.agreement = double(near) / double(frame_camera_best_.size());
  // Each quarter of the image with its share of the edges on its own: a camera of another focal
  // length moves the colour off the silhouettes everywhere, outwards or inwards, and the camera
  // found must fit all quarters but one better than the depth camera's place does (one may hold
  // silhouettes of little contrast, or ones the colour camera sees past).
  const int all_edges =
      quarter_edges_[0] + quarter_edges_[1] + quarter_edges_[2] + quarter_edges_[3];
  std::vector<double> gains;
  for (std::size_t k = 0; k < 4; ++k) {
    if (quarter_edges_[k] < kMinQuarterShare * all_edges) continue;
    const double there = quarter_sum_[k][at_one];
    gains.push_back(there > 0.0 ? quarter_sum_[k][best_camera] / there : 0.0);
  }
  std::sort(gains.begin(), gains.end());
  verdict_.quarter_gain = gains.size() >= 3 ? gains[1] : (gains.empty() ? 0.0 : gains[0]);
  // The focal ratio alone (every edge pixel, no baseline) that fits best near the camera's: what
  // the default resampling uses, so it too must be away from 1 (and from the grid's ends).
  const auto near_first = sum_.begin() + std::max(0, best - within);
  const auto near_last = sum_.begin() + std::min(kRatios, best + within + 1);
  const int alone = int(std::max_element(near_first, near_last) - sum_.begin());
  verdict_.best_ratio = ratioAt(alone);
  const bool a_camera = !atGridEnd(best) && !atGridEnd(alone) && std::abs(best - one) >= offset &&
                        std::abs(alone - one) >= offset;
  // Before frames_needed, "unregistered" on evidence that more frames would not overturn: every
  // frame's own best camera near the one found, and gains well beyond the final rule's. Each
  // frame before the verdict is registered with its colour where the other camera put it.
  if (!final) {
    if (a_camera && verdict_.agreement >= 1.0 && verdict_.gain >= options_.early_gain &&
        verdict_.quarter_gain >= options_.early_quarter_gain) {
      verdict_.state = State::kUnregistered;
    }
    return;
  }
  const bool unregistered = a_camera && verdict_.gain >= options_.min_gain &&
                            verdict_.agreement >= options_.min_agreement &&
                            verdict_.quarter_gain >= options_.min_quarter_gain;
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
      if (atGridEnd(int(std::lround((v.grid_ratio - ratioAt(0)) / kRatioStep)))) {
        std::snprintf(text, sizeof text,
                      "colour/depth registration: taken as registered, no focal ratio stands out "
                      "(the colour edges' score still climbs at the search's end, ratio %.2f, "
                      "%.2fx ratio 1's score, %d frames). If the depth comes from a second "
                      "camera, register it to the colour (depth_image_proc/register)",
                      v.grid_ratio, v.gain, v.frames);
        break;
      }
      std::snprintf(text, sizeof text,
                    "colour/depth registration: the colour edges lie on the depth edges (no "
                    "other colour camera stands out: the best, focal ratio %.2f with its centre "
                    "%.1f cm along x, scores %.2fx the images as given; %d frames)",
                    v.grid_ratio, 100.0 * v.grid_baseline, v.gain, v.frames);
      break;
    case State::kUnregistered:
      std::snprintf(text, sizeof text,
                    "the depth image does not look registered to the colour image: the colour "
                    "edges fit the depth edges best with the colour focal length %.2f times the "
                    "depth's (%d frames; as a camera beside the depth camera: %.2f times, its "
                    "centre %.0f cm along x, %.1fx the score as given). acvo needs depth "
                    "registered pixel for pixel to the colour camera: use the driver's "
                    "depth_registered image (openni2_launch depth_registration:=true, "
                    "realsense2_camera align_depth:=true) or depth_image_proc/register",
                    v.best_ratio, v.frames, v.grid_ratio, 100.0 * v.grid_baseline, v.gain);
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
  if (frame.color.empty() || !(ratio > 0.0) || ratio == 1.0) return frame;
  const Camera& c = frame.camera;
  Frame out = frame;
  out.color = cv::Mat();  // a new image: the frame's own is shared, not written
  const cv::Mat& colour = frame.color;
  // Scaling about the principal point: cv::warpAffine with the map from each output pixel to
  // where it is read.
  const cv::Matx23d to_colour(ratio, 0.0, c.cx * (1.0 - ratio), 0.0, ratio, c.cy * (1.0 - ratio));
  cv::warpAffine(colour, out.color, to_colour, colour.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REPLICATE);
  if (ratio > 1.0 && !frame.depth.empty()) {
    // The colour image's reach is a rectangle: the columns and rows it covers, once each.
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
