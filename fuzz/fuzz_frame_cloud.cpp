// Fuzz target: arbitrary bytes -> a small RGB-D frame -> labelled cloud -> registration ->
// odometry, and the colour/depth registration check. Whatever the images and intrinsics hold
// (NaN or infinite depth, zero or negative focal lengths, mismatched sizes), nothing may crash,
// the odometry pose stays finite and the check's figures too.
//
// Input layout (every read past the end gives zeros):
//   byte 0, 1   width, height: 8 + b % 89 (8..96 pixels)
//   byte 2      flags: bits 0-1 colour order (0 RGB, 1 BGR, 2 grey, 3 grey order on a 3-channel
//               image), bit 2 16-bit depth (else float), bit 3 float depth put into the frame as
//               is (else through depthToMeters), bit 4 depth from the bytes as they are (else a
//               slanted plane with holes and bumps from the bytes), bit 5 intrinsics as raw
//               doubles (else sane values from single bytes), bit 6 camera size off by one
//   byte 3, 4   shift of the second frame in pixels (-4..3 each)
//   byte 5      selection target: 20 + b points
//   then        intrinsics: raw fx fy cx cy depth_scale doubles, or 4 bytes (fx fy cx cy)
//   then        6 bytes: the guess given to align() for the shifted frame
//   the rest    colour then depth bytes, repeated to fill the images
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <tbb/global_control.h>
#include <opencv2/imgproc.hpp>

#include "acvo/cloud/colour_depth_check.hpp"
#include "acvo/cloud/depth.hpp"
#include "acvo/cloud/frame.hpp"
#include "acvo/registration/coarse_to_fine.hpp"
#include "acvo/registration/paper.hpp"
#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/math/se3.hpp"
#include "fuzz_input.hpp"

#define FUZZ_CHECK(cond)                                                                  \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "fuzz check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (false)

namespace {

using acvo::fuzz::Input;

// Cycles through the payload bytes; zeros when there are none.
class Tiles {
 public:
  Tiles(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t at(std::size_t k) const { return size_ ? data_[k % size_] : 0; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
};

struct Decoded {
  acvo::Frame frame;
  int shift_x = 0, shift_y = 0;
  acvo::Params params;
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
};

cv::Mat colourImage(int w, int h, int channels, const Tiles& tiles) {
  cv::Mat image(h, w, channels == 3 ? CV_8UC3 : CV_8UC1);
  std::size_t k = 0;
  for (int v = 0; v < h; ++v) {
    auto* row = image.ptr<std::uint8_t>(v);
    for (int i = 0; i < w * channels; ++i) row[i] = tiles.at(k++);
  }
  return image;
}

// Depth in the raw unit: `scale` raw units per metre.
double proceduralDepth(int u, int v, int w, int h, std::uint8_t b) {
  if (b < 16) return 0.0;  // holes
  return 0.8 + 2.0 * (u + 0.5 * v) / (w + h) + (b % 8 == 0 ? 0.3 : 0.0) + 1e-3 * b;
}

cv::Mat depthImage(int w, int h, bool sixteen_bit, bool from_bytes, double scale,
                   const Tiles& tiles, std::size_t offset) {
  cv::Mat raw(h, w, sixteen_bit ? CV_16UC1 : CV_32FC1);
  const std::size_t bytes = sixteen_bit ? 2 : 4;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t k = offset + (static_cast<std::size_t>(v) * w + u) * bytes;
      if (from_bytes) {
        std::uint8_t b[4] = {tiles.at(k), tiles.at(k + 1), tiles.at(k + 2), tiles.at(k + 3)};
        if (sixteen_bit) {
          raw.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(b[0] | (b[1] << 8));
        } else {
          float f;
          std::memcpy(&f, b, sizeof f);
          raw.at<float>(v, u) = f;
        }
      } else {
        const double z = proceduralDepth(u, v, w, h, tiles.at(k)) * scale;
        if (sixteen_bit) {
          raw.at<std::uint16_t>(v, u) =
              static_cast<std::uint16_t>(std::min(std::max(z, 0.0), 65535.0));
        } else {
          raw.at<float>(v, u) = static_cast<float>(z);
        }
      }
    }
  }
  return raw;
}

Decoded decode(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  Decoded d;
  const int w = 8 + in.byte() % 89, h = 8 + in.byte() % 89;
  const std::uint8_t flags = in.byte();
  const int order = flags & 3;
  const bool sixteen_bit = flags & 4, float_as_is = flags & 8, depth_from_bytes = flags & 16,
             raw_intrinsics = flags & 32, size_off = flags & 64;
  d.shift_x = in.byte() % 8 - 4;
  d.shift_y = in.byte() % 8 - 4;
  d.params.selection.target_points = 20 + in.byte();
  // Fewer iterations than the defaults keep a run short; every exit of the loops stays reachable.
  d.params.paper.max_iterations = 30;
  d.params.odometry.threads = 1;

  acvo::Camera& cam = d.frame.camera;
  cam.width = w + (size_off ? 1 : 0);
  cam.height = h;
  if (raw_intrinsics) {
    cam.fx = in.raw<double>();
    cam.fy = in.raw<double>();
    cam.cx = in.raw<double>();
    cam.cy = in.raw<double>();
    cam.depth_scale = in.raw<double>();
  } else {
    cam.fx = in.unit(0.2, 3.0) * w;
    cam.fy = in.unit(0.2, 3.0) * w;
    cam.cx = in.unit(-0.5, 1.5) * w;
    cam.cy = in.unit(-0.5, 1.5) * h;
    cam.depth_scale = sixteen_bit ? 5000.0 : 1.0;
  }
  acvo::Vector6d xi;
  for (int k = 0; k < 6; ++k) xi[k] = in.unit(-0.3, 0.3);
  d.guess = acvo::expSE3(xi);

  const Tiles tiles(in.rest(), in.restSize());
  const int channels = order == 2 ? 1 : 3;
  d.frame.order = order == 0   ? acvo::ColorOrder::kRgb
                  : order == 1 ? acvo::ColorOrder::kBgr
                               : acvo::ColorOrder::kGray;
  d.frame.color = colourImage(w, h, channels, tiles);
  const double scale =
      std::isfinite(cam.depth_scale) && cam.depth_scale > 0 ? cam.depth_scale : 1.0;
  const cv::Mat raw = depthImage(w, h, sixteen_bit, depth_from_bytes, scale, tiles,
                                 static_cast<std::size_t>(w) * h * channels);
  if (!sixteen_bit && float_as_is) {
    d.frame.depth = raw;  // NaN, Inf and negative depths reach the selector as they are
  } else {
    try {
      d.frame.depth = acvo::depthToMeters(raw, cam.depth_scale);
    } catch (const std::invalid_argument&) {
      FUZZ_CHECK(!(cam.depth_scale > 0.0) || !std::isfinite(cam.depth_scale));
      d.frame.depth = raw.type() == CV_32FC1 ? raw : cv::Mat(raw.size(), CV_32FC1, cv::Scalar(1.0));
    }
  }
  d.frame.stamp = 10.0;
  return d;
}

acvo::Frame shifted(const acvo::Frame& f, int dx, int dy) {
  acvo::Frame out = f;
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::warpAffine(f.color, out.color, m, f.color.size(), cv::INTER_NEAREST, cv::BORDER_REPLICATE);
  cv::warpAffine(f.depth, out.depth, m, f.depth.size(), cv::INTER_NEAREST, cv::BORDER_REPLICATE);
  out.stamp = f.stamp + 1.0 / 30.0;
  return out;
}

bool finite(const Eigen::Isometry3d& T) {
  return T.matrix().allFinite();
}

void checkCloud(const acvo::LabelledCloud& c, const acvo::Frame& f) {
  FUZZ_CHECK(c.labels.size() == c.size() && c.pixels.size() == c.size() &&
             c.rgb.size() == c.size());
  FUZZ_CHECK(c.width == f.color.cols && c.height == f.color.rows);
  for (std::size_t k = 0; k < c.size(); ++k) {
    const cv::Point p = c.pixels[k];
    FUZZ_CHECK(p.x >= 4 && p.y >= 4 && p.x < c.width - 4 && p.y < c.height - 4);
    const float z = f.depth.at<float>(p);
    FUZZ_CHECK(z > 0.f && std::isfinite(z));
    FUZZ_CHECK(c.labels[k].allFinite());
    FUZZ_CHECK(c.labels[k].head<3>().minCoeff() >= 0.f && c.labels[k].head<3>().maxCoeff() <= 1.f);
    FUZZ_CHECK(c.labels[k].tail<2>().cwiseAbs().maxCoeff() <= 1.f);
  }
}

void checkSolverResult(const acvo::SolverResult& r) {
  FUZZ_CHECK(finite(r.transform));
  FUZZ_CHECK(!r.paper || std::isfinite(r.paper->inner_product));
}

// The check takes any frame (a bad one is ignored) and decides on two with a single edge pixel.
void checkColourDepth(const acvo::Frame& a, const acvo::Frame& b) {
  acvo::ColourDepthCheck::Options options;
  options.min_edge_pixels = 1;
  options.frames_needed = 2;
  acvo::ColourDepthCheck check(options);
  check.add(a);
  check.add(b);
  const auto& v = check.verdict();
  FUZZ_CHECK(std::isfinite(v.best_ratio) && std::isfinite(v.gain) && v.gain >= 1.0);
  FUZZ_CHECK(v.agreement >= 0.0 && v.agreement <= 1.0 && v.frames <= v.frames_seen);
  FUZZ_CHECK(!check.describe().empty());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // One thread: runs are shorter (no pool to wake) and a crash reproduces exactly.
  static const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const Decoded d = decode(data, size);
  const acvo::Frame& frame = d.frame;

  acvo::Odometry odometry(d.params);
  if (!frame.problem().empty()) {
    checkColourDepth(frame, frame);
    bool threw = false;
    try {
      acvo::buildLabelledCloud(frame, d.params.selection);
    } catch (const std::invalid_argument&) {
      threw = true;
    }
    FUZZ_CHECK(threw);
    const acvo::OdometryResult r = odometry.process(frame);
    FUZZ_CHECK(r.tracking == acvo::Tracking::kBadFrame && !r.message.empty());
    FUZZ_CHECK(finite(r.pose));
    return 0;
  }

  const acvo::Frame moved = shifted(frame, d.shift_x, d.shift_y);
  FUZZ_CHECK(moved.problem().empty());
  checkColourDepth(frame, moved);
  const acvo::LabelledCloud cloud = acvo::buildLabelledCloud(frame, d.params.selection);
  checkCloud(cloud, frame);
  const acvo::LabelledCloud moved_cloud = acvo::buildLabelledCloud(moved, d.params.selection);
  checkCloud(moved_cloud, moved);

  // Both engines, on the same clouds.
  const auto a = acvo::prepareCoarseToFine(cloud, d.params.coarse_to_fine, true);
  const auto b = acvo::prepareCoarseToFine(moved_cloud, d.params.coarse_to_fine, false);
  checkSolverResult(
      acvo::alignCoarseToFine(*a, *a, Eigen::Isometry3d::Identity(), d.params.coarse_to_fine));
  checkSolverResult(acvo::alignCoarseToFine(*a, *b, d.guess, d.params.coarse_to_fine));
  const auto pa = acvo::preparePaper(cloud, d.params.paper, true);
  const auto pb = acvo::preparePaper(moved_cloud, d.params.paper, false);
  checkSolverResult(acvo::alignPaper(*pa, *pa, Eigen::Isometry3d::Identity(), d.params.paper));
  checkSolverResult(acvo::alignPaper(*pa, *pb, d.guess, d.params.paper));

  for (const acvo::Frame* f : {&frame, &moved, &frame}) {
    const acvo::OdometryResult r = odometry.process(*f);
    FUZZ_CHECK(r.tracking != acvo::Tracking::kBadFrame);
    FUZZ_CHECK(finite(r.pose) && finite(r.motion));
    FUZZ_CHECK(r.motion_covariance.allFinite());
    FUZZ_CHECK(finite(odometry.pose()));
  }
  return 0;
}
