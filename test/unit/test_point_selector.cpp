// Properties of the DSO-style selection (docs/method.md §1): determinism, count near the target,
// border and depth rules, Canny fallback.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "../../src/core/cloud/selection_maps.hpp"
#include "acvo/cloud/depth.hpp"
#include "acvo/cloud/point_selector.hpp"
#include "test_support.hpp"

namespace acvo {
namespace {

// Multi-scale value noise: uniform noise at several scales, upsampled and summed, so every
// block has texture at several frequencies (like a real scene, unlike white noise).
cv::Mat texturedImage(int width, int height, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat sum(height, width, CV_32FC1, cv::Scalar(0));
  float weight = 1.f;
  for (int cell : {64, 16, 4, 1}) {
    cv::Mat coarse(height / cell + 2, width / cell + 2, CV_32FC1);
    rng.fill(coarse, cv::RNG::UNIFORM, 0.f, 1.f);
    cv::Mat up;
    cv::resize(coarse, up, cv::Size(coarse.cols * cell, coarse.rows * cell), 0, 0,
               cv::INTER_LINEAR);
    sum += weight * up(cv::Rect(0, 0, width, height));
    weight *= 0.6f;
  }
  cv::Mat gray;
  cv::normalize(sum, sum, 0, 255, cv::NORM_MINMAX);
  sum.convertTo(gray, CV_8UC1);
  return gray;
}

cv::Mat constantDepth(cv::Size size, float metres) {
  return cv::Mat(size, CV_32FC1, cv::Scalar(metres));
}

bool isRowMajor(const std::vector<cv::Point>& px) {
  for (std::size_t i = 1; i < px.size(); ++i) {
    const cv::Point a = px[i - 1], b = px[i];
    if (!(a.y < b.y || (a.y == b.y && a.x < b.x))) return false;
  }
  return true;
}

TEST(PointSelector, SameImageGivesSamePixelsInRowMajorOrder) {
  const cv::Mat gray = texturedImage(640, 480, 7);
  const cv::Mat depth = constantDepth(gray.size(), 2.f);
  const Selection a = selectPixels(gray, depth, SelectionParams());
  const Selection b = selectPixels(gray.clone(), depth.clone(), SelectionParams());
  ASSERT_FALSE(a.pixels.empty());
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_EQ(a.cell_size, b.cell_size);
  EXPECT_TRUE(isRowMajor(a.pixels));
}

TEST(PointSelector, CountOnTexturedImageIsWithinFivePercentOfTarget) {
  for (std::uint64_t seed : {1, 2, 3}) {
    for (int target : {3000, 1500}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", target " + std::to_string(target));
      const cv::Mat gray = texturedImage(640, 480, seed);
      SelectionParams params;
      params.target_points = target;
      const Selection s = selectPixels(gray, constantDepth(gray.size(), 2.f), params);
      EXPECT_NEAR(static_cast<double>(s.pixels.size()), target, 0.05 * target);
      EXPECT_EQ(static_cast<int>(s.pixels.size()), s.gradient_pixels);
      EXPECT_FALSE(s.canny_used);
      EXPECT_GE(s.cell_size, 1);
    }
  }
}

// target_points is for 640x480: edges, where points are chosen, grow with the image's width.
TEST(PointSelector, TheTargetScalesWithTheImageWidth) {
  SelectionParams params;
  params.target_points = 4000;
  EXPECT_EQ(targetPoints(params, cv::Size(640, 480)), 4000);
  EXPECT_EQ(targetPoints(params, cv::Size(320, 240)), 2000);
  EXPECT_EQ(targetPoints(params, cv::Size(1280, 720)), 6928);  // 4000 sqrt(3)
  EXPECT_EQ(targetPoints(params, cv::Size(8, 6)), 50);
  EXPECT_EQ(targetPoints(params, cv::Size(1, 1)), 7);
  params.target_points = 1;
  EXPECT_EQ(targetPoints(params, cv::Size(1, 1)), 1);  // never none

  params.target_points = 3000;
  for (const bool scale : {true, false}) {
    params.scale_with_image = scale;
    const cv::Mat gray = texturedImage(320, 240, 5);
    const Selection s = selectPixels(gray, constantDepth(gray.size(), 2.f), params);
    const double expected = scale ? 1500.0 : 3000.0;
    EXPECT_NEAR(static_cast<double>(s.pixels.size()), expected, 0.05 * expected) << scale;
    EXPECT_EQ(targetPoints(params, gray.size()), int(expected));
  }
}

TEST(PointSelector, BorderIsNeverSelected) {
  // Strong gradients right at the edge of the image: the frame would attract the selector.
  cv::Mat gray = texturedImage(320, 240, 11);
  gray.colRange(0, 5).setTo(255);
  gray.rowRange(0, 5).setTo(0);
  gray.colRange(315, 320).setTo(0);
  gray.rowRange(235, 240).setTo(255);
  const Selection s = selectPixels(gray, constantDepth(gray.size(), 2.f), SelectionParams());
  ASSERT_FALSE(s.pixels.empty());
  for (const cv::Point& p : s.pixels) {
    ASSERT_GE(p.x, 4);
    ASSERT_GE(p.y, 4);
    ASSERT_LT(p.x, gray.cols - 4);
    ASSERT_LT(p.y, gray.rows - 4);
  }
}

TEST(PointSelector, InvalidDepthIsDroppedAfterSelection) {
  const cv::Mat gray = texturedImage(640, 480, 5);
  SelectionParams params;
  params.min_depth = 0.1;  // the range this test is written for, whatever the defaults
  params.max_depth = 6.0;
  cv::Mat depth = constantDepth(gray.size(), 2.f);
  depth.colRange(0, 128).setTo(0.f);
  depth.colRange(128, 256).setTo(std::numeric_limits<float>::quiet_NaN());
  depth.colRange(256, 384).setTo(0.05f);  // nearer than min_depth
  depth.colRange(384, 512).setTo(10.f);   // farther than max_depth
  depth.at<float>(240, 600) = 6.f;        // exactly max_depth: kept if selected
  depth.at<float>(100, 520) = 0.1f;       // exactly min_depth
  depth.rowRange(300, 480).colRange(512, 640).setTo(std::numeric_limits<float>::infinity());

  const Selection all_valid = selectPixels(gray, constantDepth(gray.size(), 2.f), params);
  const Selection s = selectPixels(gray, depth, params);
  // The selection itself does not look at depth: the same candidates, then filtered.
  EXPECT_EQ(s.gradient_pixels, all_valid.gradient_pixels);
  std::vector<cv::Point> expected;
  for (const cv::Point& p : all_valid.pixels) {
    const float d = depth.at<float>(p);
    if (d >= 0.1f && d <= 6.f) expected.push_back(p);
  }
  EXPECT_EQ(s.pixels, expected);
  ASSERT_FALSE(s.pixels.empty());
  for (const cv::Point& p : s.pixels) {
    const float d = depth.at<float>(p);
    ASSERT_TRUE(std::isfinite(d));
    ASSERT_GE(d, 0.1f);
    ASSERT_LE(d, 6.f);
    ASSERT_GE(p.x, 512);
  }
}

// A few flat rectangles whose edges are too weak for the gradient threshold (|grad I| = 5 is
// below the threshold of 7 of flat blocks) but strong enough for Canny's high threshold.
cv::Mat flatRectangles() {
  cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(100));
  gray(cv::Rect(100, 80, 120, 90)).setTo(110);
  gray(cv::Rect(350, 200, 150, 100)).setTo(90);
  gray(cv::Rect(150, 320, 60, 60)).setTo(110);
  return gray;
}

bool nearRectangleEdge(const cv::Point& p) {
  for (const cv::Rect& r :
       {cv::Rect(100, 80, 120, 90), cv::Rect(350, 200, 150, 100), cv::Rect(150, 320, 60, 60)}) {
    const bool near_x = std::abs(p.x - r.x) <= 2 || std::abs(p.x - (r.x + r.width)) <= 2;
    const bool near_y = std::abs(p.y - r.y) <= 2 || std::abs(p.y - (r.y + r.height)) <= 2;
    const bool in_x = p.x >= r.x - 2 && p.x <= r.x + r.width + 2;
    const bool in_y = p.y >= r.y - 2 && p.y <= r.y + r.height + 2;
    if ((near_x && in_y) || (near_y && in_x)) return true;
  }
  return false;
}

TEST(PointSelector, CannyFallbackAddsEdgePixelsOnLowTexture) {
  const cv::Mat gray = flatRectangles();
  const cv::Mat depth = constantDepth(gray.size(), 2.f);
  SelectionParams params;
  params.canny_fallback = false;
  const Selection without = selectPixels(gray, depth, params);
  params.canny_fallback = true;
  const Selection with = selectPixels(gray, depth, params);

  EXPECT_FALSE(without.canny_used);
  EXPECT_EQ(without.canny_pixels, 0);
  ASSERT_LT(3 * with.gradient_pixels, params.target_points);
  EXPECT_TRUE(with.canny_used);
  // Perimeter 2 * (120 + 90 + 150 + 100 + 60 + 60) = 1160 px: about one pixel per 8 px of edge.
  EXPECT_GT(with.canny_pixels, 100);
  EXPECT_EQ(with.gradient_pixels, without.gradient_pixels);
  EXPECT_EQ(static_cast<int>(with.pixels.size()), with.gradient_pixels + with.canny_pixels);
  EXPECT_TRUE(isRowMajor(with.pixels));

  const std::set<std::pair<int, int>> gradient([&] {
    std::set<std::pair<int, int>> s;
    for (const cv::Point& p : without.pixels) s.insert({p.x, p.y});
    return s;
  }());
  int added = 0;
  for (const cv::Point& p : with.pixels) {
    if (gradient.count({p.x, p.y})) continue;
    ++added;
    EXPECT_TRUE(nearRectangleEdge(p)) << "Canny pixel off the edges at " << p;
  }
  EXPECT_EQ(added, with.canny_pixels);
  // At most one added pixel per 8x8 block.
  std::set<std::pair<int, int>> blocks;
  for (const cv::Point& p : with.pixels) {
    if (!gradient.count({p.x, p.y})) {
      EXPECT_TRUE(blocks.insert({p.x / 8, p.y / 8}).second) << "two Canny pixels in block of " << p;
    }
  }
}

TEST(PointSelector, OddSizedViewGivesTheSameAsItsCopy) {
  // A view into a larger image is not continuous in memory; odd sizes leave partial blocks and
  // pyramid levels that drop a column.
  const cv::Mat big = texturedImage(640, 480, 13);
  const cv::Mat view = big(cv::Rect(17, 9, 333, 251));
  ASSERT_FALSE(view.isContinuous());
  const cv::Mat depth = constantDepth(view.size(), 2.f);
  SelectionParams params;
  params.target_points = 1000;
  const int target = targetPoints(params, view.size());
  EXPECT_EQ(target, 522);  // 1000 sqrt(333 x 251 / (640 x 480))
  const Selection a = selectPixels(view, depth, params);
  const Selection b = selectPixels(view.clone(), depth, params);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_NEAR(static_cast<double>(a.pixels.size()), target, 0.05 * target);
  for (const cv::Point& p : a.pixels) {
    ASSERT_TRUE(p.x >= 4 && p.y >= 4 && p.x < view.cols - 4 && p.y < view.rows - 4) << p;
  }
}

TEST(PointSelector, DensePassCountEqualsThePassItCounts) {
  // The selector counts its first pass (cells of one pixel) by rows instead of picking: any
  // difference would change the cell size of the pass that is kept. Sizes that are no multiple
  // of the 4x4 cells, smooth and noisy texture, flat halves (coarse fallbacks only).
  cv::RNG rng(7);
  std::size_t checked = 0, largest = 0;
  for (int it = 0; it < 200; ++it) {
    const int w = rng.uniform(9, 200), h = rng.uniform(9, 160);
    cv::Mat gray = texturedImage(w, h, std::uint64_t(it) + 1);
    if (it % 3 == 0) rng.fill(gray, cv::RNG::UNIFORM, 0, 256);
    if (it % 5 == 0) gray(cv::Rect(0, 0, w / 2, h)).setTo(100);
    if (it % 7 == 0) gray.setTo(50);
    const std::size_t counted = selection::densePassCount(gray);
    ASSERT_EQ(counted, selection::passSize(gray, 1)) << w << "x" << h << ", image " << it;
    largest = std::max(largest, counted);
    ++checked;
  }
  const cv::Mat big = texturedImage(640, 480, 3);
  EXPECT_EQ(selection::densePassCount(big), selection::passSize(big, 1));
  EXPECT_GT(largest, 1000u);  // the images had candidates to count
  EXPECT_EQ(checked, 200u);
}

// Level 0 of the candidate maps against the header's definition, the block medians taken by
// sorting: |grad I|^2 kept exactly where it is above the square of the mean over the 3x3
// neighbouring blocks (those with pixels) of (median of floor(|grad I|), clamped to 48, plus 7).
TEST(CandidateMaps, LevelZeroKeepsWhatTheBlockThresholdsDefine) {
  constexpr int kBlock = 32, kMax = 48;
  cv::Mat half_blank = texturedImage(200, 150, 7);
  half_blank(cv::Rect(0, 0, 100, 70)).setTo(90);  // blocks of one grey value: median 0
  for (const cv::Mat& gray : {texturedImage(640, 480, 3), texturedImage(97, 61, 4), half_blank}) {
    const selection::CandidatePyramid pyr = selection::candidateMaps(gray);
    const int bx = (gray.cols + kBlock - 1) / kBlock, by = (gray.rows + kBlock - 1) / kBlock;
    std::vector<float> median(std::size_t(bx) * by);
    for (int b = 0; b < by; ++b) {
      for (int a = 0; a < bx; ++a) {
        std::vector<int> bins;
        for (int v = std::max(b * kBlock, 1); v < std::min((b + 1) * kBlock, gray.rows - 1); ++v) {
          for (int u = std::max(a * kBlock, 1); u < std::min((a + 1) * kBlock, gray.cols - 1);
               ++u) {
            const double g = std::sqrt(double(selection::gradientMag2(gray, u, v)));
            bins.push_back(std::min(int(std::floor(g)), kMax));
          }
        }
        std::sort(bins.begin(), bins.end());
        // A block without such pixels (a 97-pixel wide image's last column) has no median.
        median[std::size_t(b) * bx + a] = bins.empty() ? NAN : float(bins[bins.size() / 2]);
      }
    }
    int kept = 0;
    for (int v = 1; v + 1 < gray.rows; ++v) {
      for (int u = 1; u + 1 < gray.cols; ++u) {
        const int a = u / kBlock, b = v / kBlock;
        float sum = 0.0f;
        int num = 0;
        for (int nb = std::max(b - 1, 0); nb <= std::min(b + 1, by - 1); ++nb) {
          for (int na = std::max(a - 1, 0); na <= std::min(a + 1, bx - 1); ++na) {
            const float m = median[std::size_t(nb) * bx + na];
            if (std::isnan(m)) continue;
            sum += m + 7.0f;
            ++num;
          }
        }
        const float th = sum / float(num);
        const float mag2 = selection::gradientMag2(gray, u, v);
        const float want = mag2 > th * th ? mag2 : 0.0f;
        ASSERT_EQ(pyr[0].at(u, v), want) << gray.size() << " at " << u << ", " << v;
        kept += want > 0.0f;
      }
    }
    EXPECT_GT(kept, gray.total() / 20) << gray.size();
    EXPECT_LT(kept, gray.total() / 2) << gray.size();
  }
}

TEST(PointSelector, BlankImageSelectsNothing) {
  const cv::Mat gray(120, 160, CV_8UC1, cv::Scalar(128));
  const Selection s = selectPixels(gray, constantDepth(gray.size(), 2.f), SelectionParams());
  EXPECT_TRUE(s.pixels.empty());
  EXPECT_EQ(s.gradient_pixels, 0);
  EXPECT_TRUE(s.canny_used);
  EXPECT_EQ(s.canny_pixels, 0);
}

TEST(PointSelector, KitchenFramesCountNearTarget) {
  const auto data = test::sharedDataDir();
  if (data.empty()) GTEST_SKIP() << "shared data (../shared/data) is absent";
  const auto dir = data / "kitchen7s_dev";
  std::ifstream assoc(dir / "associations.txt");
  ASSERT_TRUE(assoc) << "no associations.txt in " << dir;
  std::string line;
  int frames = 0;
  double sum_before = 0, sum_after = 0;
  int min_after = std::numeric_limits<int>::max(), max_after = 0;
  while (std::getline(assoc, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string t_rgb, rgb, t_depth, depth_file;
    fields >> t_rgb >> rgb >> t_depth >> depth_file;
    const cv::Mat gray = cv::imread((dir / rgb).string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat raw = cv::imread((dir / depth_file).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(gray.empty() || raw.empty()) << line;
    const SelectionParams params;
    const Selection s = selectPixels(gray, depthToMeters(raw, 5000.0), params);
    const int before = s.gradient_pixels + s.canny_pixels;
    const int after = static_cast<int>(s.pixels.size());
    // The cell size adapts in steps: measured mean 3929, lowest 3664 (8.4% under) for 4000.
    EXPECT_NEAR(before, params.target_points, 0.12 * params.target_points) << rgb;
    EXPECT_GT(after, 0.75 * before) << rgb;
    sum_before += before;
    sum_after += after;
    min_after = std::min(min_after, after);
    max_after = std::max(max_after, after);
    ++frames;
  }
  ASSERT_EQ(frames, 50);
  std::cout << "kitchen7s_dev: mean " << sum_before / frames << " selected, mean "
            << sum_after / frames << " with valid depth (min " << min_after << ", max " << max_after
            << ")\n";
}

}  // namespace
}  // namespace acvo
