// The labelled cloud (docs/method.md §1): HSV from the real channel order, gradient labels,
// back-projection, and the cost of building a cloud from a Kinect frame.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "acvo/cloud/depth.hpp"
#include "acvo/cloud/hsv.hpp"
#include "acvo/cloud/labelled_cloud.hpp"
#include "test_support.hpp"

namespace acvo {
namespace {

Camera cameraFor(cv::Size size, double fx = 585, double fy = 585) {
  Camera c;
  c.fx = fx;
  c.fy = fy;
  c.cx = size.width / 2.0;
  c.cy = size.height / 2.0;
  c.width = size.width;
  c.height = size.height;
  return c;
}

Frame frameOf(const cv::Mat& color, ColorOrder order, float depth_m = 2.f) {
  Frame f;
  f.color = color;
  f.order = order;
  f.depth = cv::Mat(color.size(), CV_32FC1, cv::Scalar(depth_m));
  f.camera = cameraFor(color.size());
  f.stamp = 12.5;
  return f;
}

// Squares of pure red, green, blue and black (RGB order), 16 px wide: every edge between two
// of them is strong, so pixels of each colour get selected.
cv::Mat primaries() {
  const std::array<cv::Vec3b, 4> colours = {cv::Vec3b(255, 0, 0), cv::Vec3b(0, 255, 0),
                                            cv::Vec3b(0, 0, 255), cv::Vec3b(0, 0, 0)};
  cv::Mat rgb(240, 320, CV_8UC3);
  for (int v = 0; v < rgb.rows; ++v) {
    for (int u = 0; u < rgb.cols; ++u)
      rgb.at<cv::Vec3b>(v, u) = colours[(u / 16 + 3 * (v / 16)) % 4];
  }
  return rgb;
}

TEST(LabelledCloud, PrimariesGiveOpenCvHueInEitherChannelOrder) {
  const cv::Mat rgb = primaries();
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  const LabelledCloud a = buildLabelledCloud(frameOf(rgb, ColorOrder::kRgb), SelectionParams());
  const LabelledCloud b = buildLabelledCloud(frameOf(bgr, ColorOrder::kBgr), SelectionParams());
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  std::array<int, 4> seen{};
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.pixels[i], b.pixels[i]);
    ASSERT_EQ(a.rgb[i], b.rgb[i]);
    ASSERT_EQ(a.labels[i], b.labels[i]);
    const cv::Vec3b c = rgb.at<cv::Vec3b>(a.pixels[i]);
    EXPECT_EQ(a.rgb[i], (std::array<std::uint8_t, 3>{c[0], c[1], c[2]}));
    const Label& l = a.labels[i];
    if (c == cv::Vec3b(255, 0, 0)) {
      EXPECT_FLOAT_EQ(l[0], 0.f);
      ++seen[0];
    } else if (c == cv::Vec3b(0, 255, 0)) {
      EXPECT_FLOAT_EQ(l[0], 60.f / 180.f);
      ++seen[1];
    } else if (c == cv::Vec3b(0, 0, 255)) {
      EXPECT_FLOAT_EQ(l[0], 120.f / 180.f);
      ++seen[2];
    } else {
      EXPECT_FLOAT_EQ(l[2], 0.f);  // black: V = 0
      ++seen[3];
      continue;
    }
    EXPECT_FLOAT_EQ(l[1], 1.f);
    EXPECT_FLOAT_EQ(l[2], 1.f);
  }
  for (int n : seen) EXPECT_GT(n, 10);
}

TEST(LabelledCloud, GrayFrameHasNoHueOrSaturation) {
  cv::Mat gray(240, 320, CV_8UC1);
  cv::RNG rng(3);
  rng.fill(gray, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(gray, gray, cv::Size(5, 5), 1.5);
  const LabelledCloud c = buildLabelledCloud(frameOf(gray, ColorOrder::kGray), SelectionParams());
  ASSERT_GT(c.size(), 100u);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const std::uint8_t g = gray.at<std::uint8_t>(c.pixels[i]);
    EXPECT_EQ(c.rgb[i], (std::array<std::uint8_t, 3>{g, g, g}));
    EXPECT_EQ(c.labels[i][0], 0.f);
    EXPECT_EQ(c.labels[i][1], 0.f);
    EXPECT_FLOAT_EQ(c.labels[i][2], g / 255.f);
  }
}

TEST(LabelledCloud, HsvOfEveryColourEqualsCvtColor) {
  // All 2^24 colours, one per pixel.
  cv::Mat rgb(4096, 4096, CV_8UC3);
  for (int i = 0; i < (1 << 24); ++i) {
    rgb.at<cv::Vec3b>(i >> 12, i & 4095) = cv::Vec3b(i >> 16, (i >> 8) & 255, i & 255);
  }
  cv::Mat hsv;
  cv::cvtColor(rgb, hsv, cv::COLOR_RGB2HSV);
  int mismatches = 0;
  for (int i = 0; i < (1 << 24); ++i) {
    const cv::Vec3b want = hsv.at<cv::Vec3b>(i >> 12, i & 4095);
    const auto got = rgbToHsv(i >> 16, (i >> 8) & 255, i & 255);
    if (got[0] != want[0] || got[1] != want[1] || got[2] != want[2]) {
      if (++mismatches <= 5) {
        ADD_FAILURE() << "rgb " << (i >> 16) << " " << ((i >> 8) & 255) << " " << (i & 255)
                      << ": got " << int(got[0]) << " " << int(got[1]) << " " << int(got[2])
                      << ", cvtColor " << want;
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
}

TEST(LabelledCloud, LabelsOfATexturedFrameMatchCvtColorAndCentralDifferences) {
  cv::Mat rgb(240, 320, CV_8UC3);
  cv::RNG rng(9);
  rng.fill(rgb, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(rgb, rgb, cv::Size(7, 7), 2.0);
  cv::Mat bgr, hsv, gray;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::cvtColor(rgb, hsv, cv::COLOR_RGB2HSV);
  cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
  const LabelledCloud c = buildLabelledCloud(frameOf(bgr, ColorOrder::kBgr), SelectionParams());
  ASSERT_GT(c.size(), 1000u);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const cv::Point p = c.pixels[i];
    const cv::Vec3b want = hsv.at<cv::Vec3b>(p);
    const Label& l = c.labels[i];
    ASSERT_FLOAT_EQ(l[0], want[0] / 180.f) << p;
    ASSERT_FLOAT_EQ(l[1], want[1] / 255.f) << p;
    ASSERT_FLOAT_EQ(l[2], want[2] / 255.f) << p;
    const float gx =
        0.5f * (gray.at<std::uint8_t>(p.y, p.x + 1) - gray.at<std::uint8_t>(p.y, p.x - 1));
    const float gy =
        0.5f * (gray.at<std::uint8_t>(p.y + 1, p.x) - gray.at<std::uint8_t>(p.y - 1, p.x));
    ASSERT_FLOAT_EQ(l[3], gx / 255.f * 2.f) << p;
    ASSERT_FLOAT_EQ(l[4], gy / 255.f * 2.f) << p;
  }
}

TEST(LabelledCloud, GradientLabelsOnAKnownRamp) {
  // Flat grey except a ramp I = 8 u + 6 v (+ offset) in a square: inside it gx = 8, gy = 6, so
  // the labels are 8 / 255 * 2 and 6 / 255 * 2. The flat surroundings keep the threshold low.
  cv::Mat gray(96, 96, CV_8UC1, cv::Scalar(0));
  const cv::Rect ramp(40, 40, 16, 16);
  for (int v = ramp.y; v < ramp.y + ramp.height; ++v) {
    for (int u = ramp.x; u < ramp.x + ramp.width; ++u) {
      gray.at<std::uint8_t>(v, u) =
          static_cast<std::uint8_t>(8 * (u - ramp.x) + 6 * (v - ramp.y) + 20);
    }
  }
  const LabelledCloud c = buildLabelledCloud(frameOf(gray, ColorOrder::kGray), SelectionParams());
  int inside = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const cv::Point p = c.pixels[i];
    if (p.x <= ramp.x || p.y <= ramp.y || p.x >= ramp.x + ramp.width - 1 ||
        p.y >= ramp.y + ramp.height - 1) {
      continue;
    }
    ++inside;
    EXPECT_FLOAT_EQ(c.labels[i][3], 16.f / 255.f) << p;
    EXPECT_FLOAT_EQ(c.labels[i][4], 12.f / 255.f) << p;
  }
  EXPECT_GT(inside, 10);
}

TEST(LabelledCloud, BackProjectionUsesTheIntrinsics) {
  const cv::Mat rgb = primaries();
  Frame f = frameOf(rgb, ColorOrder::kRgb, 2.f);
  f.depth.colRange(160, 320).setTo(3.f);
  const LabelledCloud first = buildLabelledCloud(f, SelectionParams());
  ASSERT_GT(first.size(), 2u);
  // Put the principal point on a selected pixel (selection does not depend on the camera).
  const cv::Point c = first.pixels[first.size() / 2];
  f.camera.fx = 500;
  f.camera.fy = 400;
  f.camera.cx = c.x;
  f.camera.cy = c.y;
  const LabelledCloud cloud = buildLabelledCloud(f, SelectionParams());
  ASSERT_EQ(cloud.pixels, first.pixels);
  const float dc = f.depth.at<float>(c);
  const Eigen::Vector3f& centre = cloud.points[first.size() / 2];
  EXPECT_EQ(centre, Eigen::Vector3f(0.f, 0.f, dc));
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const cv::Point p = cloud.pixels[i];
    const float z = p.x < 160 ? 2.f : 3.f;
    ASSERT_FLOAT_EQ(cloud.points[i].z(), z);
    ASSERT_NEAR(cloud.points[i].x(), (p.x - c.x) * z / 500.f, 1e-6);
    ASSERT_NEAR(cloud.points[i].y(), (p.y - c.y) * z / 400.f, 1e-6);
  }
  // A pixel 50 columns right and 40 rows below the principal point at 2 m: (0.2, 0.2, 2).
  const Eigen::Vector3d q = f.camera.backProject(c.x + 50, c.y + 40, 2.0);
  EXPECT_NEAR(q.x(), 0.2, 1e-12);
  EXPECT_NEAR(q.y(), 0.2, 1e-12);
}

TEST(LabelledCloud, CarriesStampSizeAndStats) {
  const cv::Mat rgb = primaries();
  const Frame f = frameOf(rgb, ColorOrder::kRgb);
  CloudStats stats;
  const LabelledCloud c = buildLabelledCloud(f, SelectionParams(), &stats);
  EXPECT_EQ(c.stamp, 12.5);
  EXPECT_EQ(c.width, 320);
  EXPECT_EQ(c.height, 240);
  EXPECT_EQ(c.points.size(), c.size());
  EXPECT_EQ(c.labels.size(), c.size());
  EXPECT_EQ(c.rgb.size(), c.size());
  cv::Mat gray;
  cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
  const Selection direct = selectPixels(gray, f.depth, SelectionParams());
  EXPECT_EQ(c.pixels, direct.pixels);
  EXPECT_EQ(stats.selection.gradient_pixels, direct.gradient_pixels);
  EXPECT_EQ(stats.selection.canny_pixels, direct.canny_pixels);
  EXPECT_EQ(stats.selection.cell_size, direct.cell_size);
  EXPECT_GT(stats.ms_selection, 0.0);
  EXPECT_GT(stats.ms_labels, 0.0);
}

// The same pixels with another depth image: their points from it, the pixels it has no usable
// depth for dropped, each label, colour and pixel still its own.
TEST(LabelledCloud, WithDepthKeepsThePixelsAndTakesTheirPointsFromTheNewDepth) {
  const Frame f = frameOf(primaries(), ColorOrder::kRgb, 2.f);
  const SelectionParams params;
  const LabelledCloud cloud = buildLabelledCloud(f, params);
  ASSERT_GT(cloud.size(), 10u);

  // The same depth: the same cloud.
  const LabelledCloud same = withDepth(cloud, f.depth, params);
  EXPECT_EQ(same.pixels, cloud.pixels);
  EXPECT_EQ(same.points, cloud.points);
  EXPECT_EQ(same.rgb, cloud.rgb);
  ASSERT_EQ(same.labels.size(), cloud.labels.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) EXPECT_EQ(same.labels[i], cloud.labels[i]);
  EXPECT_EQ(same.stamp, cloud.stamp);

  // Right of column 160 the surface is at 3 m; the first selected pixel loses its depth, the
  // second's is beyond max_depth, the third's NaN.
  cv::Mat depth = f.depth.clone();
  depth.colRange(160, depth.cols).setTo(3.f);
  depth.at<float>(cloud.pixels[0]) = 0.f;
  depth.at<float>(cloud.pixels[1]) = float(params.max_depth) + 0.5f;
  depth.at<float>(cloud.pixels[2]) = std::nanf("");
  const LabelledCloud moved = withDepth(cloud, depth, params);
  ASSERT_EQ(moved.size(), cloud.size() - 3);
  EXPECT_EQ(moved.labels.size(), moved.size());
  EXPECT_EQ(moved.rgb.size(), moved.size());
  EXPECT_EQ(moved.pixels.size(), moved.size());
  EXPECT_EQ(moved.depth.data, depth.data);
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const std::size_t j = i + 3;  // the first three are gone
    ASSERT_EQ(moved.pixels[i], cloud.pixels[j]);
    EXPECT_EQ(moved.rgb[i], cloud.rgb[j]);
    EXPECT_EQ(moved.labels[i], cloud.labels[j]);
    const cv::Point p = moved.pixels[i];
    const double z = p.x < 160 ? 2.0 : 3.0;
    EXPECT_TRUE(moved.points[i].isApprox(f.camera.backProject(p.x, p.y, z).cast<float>()));
  }
  EXPECT_THROW(withDepth(cloud, cv::Mat(10, 10, CV_32FC1), params), std::invalid_argument);
}

TEST(LabelledCloud, RejectsUnusableFrames) {
  Frame f = frameOf(primaries(), ColorOrder::kRgb);
  f.depth = cv::Mat();
  EXPECT_THROW(buildLabelledCloud(f, SelectionParams()), std::invalid_argument);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

TEST(LabelledCloud, KitchenFramesGiveFullCloudsWithinTheDepthRange) {
  const auto data = test::sharedDataDir();
  if (data.empty()) GTEST_SKIP() << "shared data (../shared/data) is absent";
  const auto dir = data / "kitchen7s_dev";
  std::ifstream assoc(dir / "associations.txt");
  ASSERT_TRUE(assoc) << "no associations.txt in " << dir;
  std::vector<Frame> frames;
  std::string line;
  while (std::getline(assoc, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string t_rgb, rgb, t_depth, depth_file;
    fields >> t_rgb >> rgb >> t_depth >> depth_file;
    Frame f;
    f.color = cv::imread((dir / rgb).string(), cv::IMREAD_COLOR);
    f.order = ColorOrder::kBgr;
    f.depth = depthToMeters(cv::imread((dir / depth_file).string(), cv::IMREAD_UNCHANGED), 5000.0);
    f.camera = cameraFor(f.color.size());
    f.camera.cx = 320;
    f.camera.cy = 240;
    f.stamp = std::stod(t_rgb);
    ASSERT_TRUE(f.problem().empty()) << f.problem();
    frames.push_back(f);
  }
  ASSERT_EQ(frames.size(), 50u);
  std::vector<double> total, sel, lab, points;
  for (const Frame& f : frames) {
    CloudStats stats;
    const auto t0 = std::chrono::steady_clock::now();
    const SelectionParams params;
    const LabelledCloud c = buildLabelledCloud(f, params, &stats);
    total.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    sel.push_back(stats.ms_selection);
    lab.push_back(stats.ms_labels);
    points.push_back(static_cast<double>(c.size()));
    EXPECT_NEAR(stats.selection.gradient_pixels + stats.selection.canny_pixels,
                params.target_points, 0.12 * params.target_points);  // measured: down to 8.4% under
    EXPECT_GT(c.size(), 0.66 * params.target_points);
    for (const Eigen::Vector3f& p : c.points) {
      ASSERT_TRUE(p.z() >= params.min_depth && p.z() <= params.max_depth);
    }
  }
  std::cout << "kitchen7s_dev 640x480: median build " << median(total) << " ms (selection "
            << median(sel) << " ms, labels " << median(lab) << " ms), median " << median(points)
            << " points\n";
  // Speed is measured by scripts/bench, not asserted here: a timed test would flake on a
  // loaded machine.
}

}  // namespace
}  // namespace acvo
