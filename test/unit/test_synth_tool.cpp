// acvo_synth end to end: a tiny sequence on disk, its lists, groundtruth and camera file,
// determinism, an unregistered colour camera (and scripts/register_colour undoing it), a lens
// (scripts/distort_tum, undone on loading), scripts/downsample_tum, scripts/depth_distortion,
// colour taken after the depth, a swinging brightness, vignetting, and the errors for bad options.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "acvo/cloud/camera.hpp"
#include "acvo/dataset/tum.hpp"
#include "synth/layout.hpp"
#include "synth/sequence.hpp"
#include "test_support.hpp"

namespace acvo::synth {
namespace {

namespace fs = std::filesystem;

// Runs acvo_synth with `arguments`; returns its exit status.
int runTool(const std::string& arguments) {
  const fs::path tool = test::toolsDir() / "acvo_synth";
  const std::string command = "'" + tool.string() + "' " + arguments + " >/dev/null 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The non-comment lines of a text file, split into words.
std::vector<std::vector<std::string>> readRows(const fs::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    rows.emplace_back();
    for (std::string w; words >> w;) rows.back().push_back(w);
  }
  return rows;
}

std::string readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(SynthTool, WritesAConsistentTumFolder) {
  const fs::path out = test::tempDir("synth_tool");
  ASSERT_EQ(runTool("'" + out.string() + "' --frames 5 --width 160 --height 120 --noise off"), 0);

  const auto rgb = readRows(out / "rgb.txt");
  const auto depth = readRows(out / "depth.txt");
  const auto assoc = readRows(out / "associations.txt");
  const auto gt = readRows(out / "groundtruth.txt");
  ASSERT_EQ(rgb.size(), 5u);
  ASSERT_EQ(depth.size(), 5u);
  ASSERT_EQ(assoc.size(), 5u);
  ASSERT_EQ(gt.size(), 5u);
  EXPECT_EQ(std::distance(fs::directory_iterator(out / "rgb"), fs::directory_iterator()), 5);
  EXPECT_EQ(std::distance(fs::directory_iterator(out / "depth"), fs::directory_iterator()), 5);

  const Camera camera = loadCameraYaml((out / "camera.yaml").string());
  const Camera expected = scaledDefaultCamera(160, 120);
  EXPECT_EQ(camera.width, 160);
  EXPECT_EQ(camera.height, 120);
  EXPECT_DOUBLE_EQ(camera.fx, expected.fx);
  EXPECT_DOUBLE_EQ(camera.fy, expected.fy);
  EXPECT_DOUBLE_EQ(camera.cx, expected.cx);
  EXPECT_DOUBLE_EQ(camera.cy, expected.cy);
  EXPECT_DOUBLE_EQ(camera.depth_scale, 5000.0);

  // The same frames, in memory, to compare the files with.
  SequenceOptions options;
  options.frames = 5;
  options.noise = false;
  options.camera = expected;
  const SynthSequence sequence(options);

  char stamp[32];
  for (int i = 0; i < 5; ++i) {
    std::snprintf(stamp, sizeof stamp, "%.6f", 1000.0 + i / 30.0);
    ASSERT_EQ(rgb[i].size(), 2u);
    ASSERT_EQ(depth[i].size(), 2u);
    ASSERT_EQ(assoc[i].size(), 4u);
    ASSERT_EQ(gt[i].size(), 8u);
    EXPECT_EQ(rgb[i][0], stamp);
    EXPECT_EQ(rgb[i][1], std::string("rgb/") + stamp + ".png");
    EXPECT_EQ(depth[i][0], stamp);
    EXPECT_EQ(depth[i][1], std::string("depth/") + stamp + ".png");
    EXPECT_EQ(assoc[i], (std::vector<std::string>{rgb[i][0], rgb[i][1], depth[i][0], depth[i][1]}));
    EXPECT_EQ(gt[i][0], stamp);

    const cv::Mat colour = cv::imread((out / rgb[i][1]).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat raw = cv::imread((out / depth[i][1]).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(colour.type(), CV_8UC3);
    ASSERT_EQ(raw.type(), CV_16UC1);
    ASSERT_EQ(colour.size(), cv::Size(160, 120));
    ASSERT_EQ(raw.size(), cv::Size(160, 120));

    const SynthFrame f = sequence.frame(i);
    EXPECT_EQ(cv::norm(colour, f.bgr, cv::NORM_INF), 0.0);
    cv::Mat metres;
    raw.convertTo(metres, CV_32F, 1.0 / 5000.0);
    EXPECT_LE(cv::norm(metres, f.depth_m, cv::NORM_INF), 0.5 / 5000.0 + 1e-6);  // PNG step only

    // Groundtruth: the exact pose, unit quaternion.
    const Eigen::Vector3d t(std::stod(gt[i][1]), std::stod(gt[i][2]), std::stod(gt[i][3]));
    const Eigen::Quaterniond q(std::stod(gt[i][7]), std::stod(gt[i][4]), std::stod(gt[i][5]),
                               std::stod(gt[i][6]));
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_GE(q.w(), 0.0);
    EXPECT_LT((t - f.pose.translation()).norm(), 1e-15);
    EXPECT_LT((q.toRotationMatrix() - f.pose.linear()).norm(), 1e-14);
  }
  EXPECT_LT(
      (Eigen::Vector3d(std::stod(gt[0][1]), std::stod(gt[0][2]), std::stod(gt[0][3])) - kStartEye)
          .norm(),
      1e-15);
}

TEST(SynthTool, SameSeedSameFilesOtherSeedOtherImages) {
  const fs::path a = test::tempDir("synth_tool_a"), b = test::tempDir("synth_tool_b"),
                 c = test::tempDir("synth_tool_c");
  const std::string common = " --frames 3 --width 96 --height 72 --blur on";
  ASSERT_EQ(runTool("'" + a.string() + "'" + common + " --seed 4"), 0);
  ASSERT_EQ(runTool("'" + b.string() + "'" + common + " --seed 4"), 0);
  ASSERT_EQ(runTool("'" + c.string() + "'" + common + " --seed 5"), 0);
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(a)) {
    if (!entry.is_regular_file()) continue;
    const fs::path relative = fs::relative(entry.path(), a);
    EXPECT_EQ(readBytes(entry.path()), readBytes(b / relative)) << relative;
    ++files;
  }
  EXPECT_EQ(files, 3 + 3 + 5);  // images, depth images, 4 lists and camera.yaml
  const std::string first = "rgb/1000.000000.png";
  EXPECT_NE(readBytes(a / first), readBytes(c / first));
  EXPECT_NE(readBytes(a / "groundtruth.txt"), readBytes(c / "groundtruth.txt"));
}

// --colour-focal-ratio and --colour-baseline change the colour images only (blurred too), and
// the lists' header says so; the default options write registered colour.
TEST(SynthTool, AnUnregisteredColourCameraChangesTheColourOnly) {
  const fs::path a = test::tempDir("synth_tool_registered"),
                 b = test::tempDir("synth_tool_unregistered");
  const std::string common = " --frames 2 --width 96 --height 72 --blur on --seed 4";
  ASSERT_EQ(runTool("'" + a.string() + "'" + common), 0);
  ASSERT_EQ(runTool("'" + b.string() + "'" + common +
                    " --colour-focal-ratio 0.897 --colour-baseline 0.025"),
            0);
  for (const std::string stamp : {"1000.000000", "1000.033333"}) {
    EXPECT_EQ(readBytes(a / "depth" / (stamp + ".png")), readBytes(b / "depth" / (stamp + ".png")));
    EXPECT_NE(readBytes(a / "rgb" / (stamp + ".png")), readBytes(b / "rgb" / (stamp + ".png")));
  }
  EXPECT_EQ(readRows(a / "groundtruth.txt"), readRows(b / "groundtruth.txt"));  // the poses
  EXPECT_EQ(readBytes(a / "camera.yaml"), readBytes(b / "camera.yaml"));
  EXPECT_EQ(readBytes(a / "rgb.txt").find("unregistered"), std::string::npos);
  EXPECT_NE(readBytes(b / "rgb.txt").find("colour unregistered: focal x0.897, baseline 0.025 m"),
            std::string::npos);
}

// Colour taken 10 ms after the depth: the colour images stamped and rendered at their own time,
// the depth as before, the ground truth at both stamps.
TEST(SynthTool, ColourTakenLaterIsRenderedAndStampedAtItsOwnTime) {
  const fs::path a = test::tempDir("synth_tool_synchronised"),
                 b = test::tempDir("synth_tool_colour_later");
  const std::string common = " --frames 3 --width 96 --height 72 --seed 4 --noise off";
  ASSERT_EQ(runTool("'" + a.string() + "'" + common), 0);
  ASSERT_EQ(runTool("'" + b.string() + "'" + common + " --colour-delay 0.01"), 0);
  const auto assoc = readRows(b / "associations.txt");
  const auto gt_a = readRows(a / "groundtruth.txt"), gt_b = readRows(b / "groundtruth.txt");
  ASSERT_EQ(assoc.size(), 3u);
  ASSERT_EQ(gt_b.size(), 6u);
  for (std::size_t i = 0; i < 3; ++i) {
    const std::string depth_stamp = assoc[i][2], colour_stamp = assoc[i][0];
    EXPECT_NEAR(std::stod(colour_stamp) - std::stod(depth_stamp), 0.01, 1e-9);
    EXPECT_EQ(readBytes(a / "depth" / (depth_stamp + ".png")),
              readBytes(b / "depth" / (depth_stamp + ".png")));
    EXPECT_TRUE(fs::exists(b / "rgb" / (colour_stamp + ".png")));
    EXPECT_EQ(gt_b[2 * i], gt_a[i]);              // the depth's pose, as without the delay
    EXPECT_EQ(gt_b[2 * i + 1][0], colour_stamp);  // then the colour's
    EXPECT_NE(gt_b[2 * i + 1], gt_a[i]);
  }
  // In memory: the colour is the rendering at the colour's pose.
  SequenceOptions o;
  o.frames = 2;
  o.noise = false;
  o.colour_delay = -0.01;
  o.camera = scaledDefaultCamera(96, 72);
  const SynthSequence seq(o);
  const SynthFrame f = seq.frame(1);
  EXPECT_DOUBLE_EQ(f.depth_stamp, seq.stamp(1));
  EXPECT_DOUBLE_EQ(f.stamp, seq.stamp(1) - 0.01);
  EXPECT_EQ(f.toFrame().depth_stamp, f.depth_stamp);
  EXPECT_TRUE(seq.colourPose(1).isApprox(seq.motion().poseAt(1.0 / 30.0 - 0.01)));
  EXPECT_EQ(
      cv::norm(f.bgr, render(seq.scene(), seq.colourPose(1), o.renderOptions()).bgr, cv::NORM_INF),
      0.0);
  EXPECT_GT(
      cv::norm(f.bgr, render(seq.scene(), seq.poses()[1], o.renderOptions()).bgr, cv::NORM_INF),
      0.0);
}

// A camera's auto exposure (--brightness-swing): each colour image is the constant one times the
// sequence's brightness at its time, which stays within 1 +- the swing, changes smoothly and
// depends on the seed; the depth and the poses are as without it.
TEST(SynthTool, BrightnessSwingScalesTheColourAlone) {
  const fs::path a = test::tempDir("synth_tool_constant"), b = test::tempDir("synth_tool_swinging");
  const std::string common = " --frames 3 --width 96 --height 72 --seed 4 --noise off";
  ASSERT_EQ(runTool("'" + a.string() + "'" + common), 0);
  ASSERT_EQ(runTool("'" + b.string() + "'" + common + " --brightness-swing 0.3"), 0);
  EXPECT_EQ(readRows(a / "groundtruth.txt"), readRows(b / "groundtruth.txt"));
  for (const auto& row : readRows(a / "depth.txt")) {
    EXPECT_EQ(readBytes(a / row[1]), readBytes(b / row[1]));
  }
  EXPECT_NE(readBytes(b / "rgb.txt").find("brightness swinging by 0.3"), std::string::npos);

  SequenceOptions o;
  o.frames = 300;
  o.noise = false;
  o.brightness_swing = 0.3;
  o.camera = scaledDefaultCamera(96, 72);
  const SynthSequence seq(o);
  double lo = 2.0, hi = 0.0, steepest = 0.0;
  for (int i = 0; i < seq.size(); ++i) {
    const double g = seq.brightness(i / o.rate);
    lo = std::min(lo, g);
    hi = std::max(hi, g);
    if (i > 0) steepest = std::max(steepest, std::abs(g - seq.brightness((i - 1) / o.rate)));
  }
  // Over 10 s the curve reaches most of its range and never changes faster than 3x the swing
  // per second.
  EXPECT_GE(lo, 0.7);
  EXPECT_LE(hi, 1.3);
  EXPECT_GT(hi - lo, 0.4);
  EXPECT_LE(steepest, 3.0 * 0.3 / o.rate);
  SequenceOptions other = o;
  other.seed = 5;
  EXPECT_NE(SynthSequence(other).brightness(0.0), seq.brightness(0.0));
  SequenceOptions constant = o;
  constant.brightness_swing = 0.0;
  EXPECT_EQ(SynthSequence(constant).brightness(1.0), 1.0);
  // Frame 7's colour is the constant rendering times its brightness (to 8-bit rounding).
  const SynthFrame f = seq.frame(7);
  cv::Mat expected;
  SynthSequence(constant).frame(7).bgr.convertTo(expected, CV_8UC3, seq.brightness(7 / o.rate));
  EXPECT_LE(cv::norm(f.bgr, expected, cv::NORM_INF), 1.0);
  EXPECT_NE(seq.brightness(7 / o.rate), 1.0);
}

// A lens's vignetting (--vignetting V): each pixel's colour is the plain one times
// exp(V rho), rho its squared distance from the principal point in focal lengths; the depth as
// without it.
TEST(SynthTool, VignettingDarkensTheColourTowardsTheCorners) {
  const fs::path a = test::tempDir("synth_tool_no_vignetting"),
                 b = test::tempDir("synth_tool_vignetting");
  const std::string common = " --frames 2 --width 96 --height 72 --seed 4 --noise off";
  ASSERT_EQ(runTool("'" + a.string() + "'" + common), 0);
  ASSERT_EQ(runTool("'" + b.string() + "'" + common + " --vignetting -1"), 0);
  for (const auto& row : readRows(a / "depth.txt")) {
    EXPECT_EQ(readBytes(a / row[1]), readBytes(b / row[1]));
  }
  EXPECT_NE(readBytes(b / "rgb.txt").find("vignetting -1"), std::string::npos);
  const auto rows = readRows(a / "rgb.txt");
  const cv::Mat plain = cv::imread((a / rows[0][1]).string());
  const cv::Mat dark = cv::imread((b / rows[0][1]).string());
  ASSERT_FALSE(plain.empty());
  ASSERT_EQ(plain.size(), dark.size());
  const Camera c = scaledDefaultCamera(96, 72);
  double worst = 0.0;
  for (int v = 0; v < plain.rows; ++v) {
    for (int u = 0; u < plain.cols; ++u) {
      const double x = (u - c.cx) / c.fx, y = (v - c.cy) / c.fy;
      const double factor = std::exp(-(x * x + y * y));
      for (int k = 0; k < 3; ++k) {
        const double expected = factor * plain.at<cv::Vec3b>(v, u)[k];
        worst = std::max(worst, std::abs(dark.at<cv::Vec3b>(v, u)[k] - expected));
      }
    }
  }
  EXPECT_LE(worst, 1.0);  // both rounded to 8 bits from the same float colour
  // A corner is darker than the centre by the factor there (0.57 for this camera).
  const cv::Point corner(0, 0);
  const double x = -c.cx / c.fx, y = -c.cy / c.fy;
  EXPECT_LT(std::exp(-(x * x + y * y)), 0.6);
  EXPECT_LT(cv::norm(dark.at<cv::Vec3b>(corner)), cv::norm(plain.at<cv::Vec3b>(corner)) + 1e-9);
}

// Depth noise in blobs (--depth-noise-correlation PX) changes the depth images alone, and only
// where there is noise.
TEST(SynthTool, DepthNoiseCorrelationChangesTheDepthAlone) {
  const fs::path a = test::tempDir("synth_tool_noise_per_pixel"),
                 b = test::tempDir("synth_tool_noise_blobs"),
                 c = test::tempDir("synth_tool_exact_blobs"), d = test::tempDir("synth_tool_exact");
  const std::string common = " --frames 2 --width 96 --height 72 --seed 4";
  ASSERT_EQ(runTool("'" + a.string() + "'" + common), 0);
  ASSERT_EQ(runTool("'" + b.string() + "'" + common + " --depth-noise-correlation 3"), 0);
  ASSERT_EQ(runTool("'" + c.string() + "'" + common + " --noise off --depth-noise-correlation 3"),
            0);
  ASSERT_EQ(runTool("'" + d.string() + "'" + common + " --noise off"), 0);
  EXPECT_NE(readBytes(b / "rgb.txt").find("depth noise correlated over 3 px"), std::string::npos);
  EXPECT_EQ(readBytes(c / "rgb.txt").find("correlated"), std::string::npos);
  for (const auto& row : readRows(a / "rgb.txt")) {
    EXPECT_EQ(readBytes(a / row[1]), readBytes(b / row[1]));
  }
  for (const auto& row : readRows(a / "depth.txt")) {
    EXPECT_NE(readBytes(a / row[1]), readBytes(b / row[1]));
    EXPECT_EQ(readBytes(c / row[1]), readBytes(d / row[1]));
  }
}

// A fixed depth distortion (--depth-distortion R) changes the depth images alone, and says so.
TEST(SynthTool, DepthDistortionChangesTheDepthAlone) {
  const fs::path a = test::tempDir("synth_tool_undistorted"),
                 b = test::tempDir("synth_tool_distorted");
  const std::string common = " --frames 2 --width 96 --height 72 --seed 4";
  ASSERT_EQ(runTool("'" + a.string() + "'" + common), 0);
  ASSERT_EQ(runTool("'" + b.string() + "'" + common + " --depth-distortion 0.01"), 0);
  EXPECT_NE(readBytes(b / "rgb.txt").find("depth distorted by 0.01"), std::string::npos);
  for (const auto& row : readRows(a / "rgb.txt")) {
    EXPECT_EQ(readBytes(a / row[1]), readBytes(b / row[1]));
  }
  for (const auto& row : readRows(a / "depth.txt")) {
    EXPECT_NE(readBytes(a / row[1]), readBytes(b / row[1]));
  }
}

// Mean absolute difference of two 8-bit colour images.
double meanDifference(const fs::path& a, const fs::path& b) {
  const cv::Mat x = cv::imread(a.string()), y = cv::imread(b.string());
  EXPECT_FALSE(x.empty()) << a;
  EXPECT_EQ(x.size(), y.size()) << b;
  if (x.empty() || x.size() != y.size()) return 1e9;
  return cv::norm(x, y, cv::NORM_L1) / double(x.total() * x.channels());
}

// scripts/register_colour with the colour camera's true parameters brings the colour of an
// unregistered rendering back to the registered one's (measured: mean difference 17.4 grey
// levels unregistered, 2.2 registered by the script, 6.8 with the focal ratio alone, 11.4 with
// the baseline's sign wrong); a folder that exists or parameters out of range are refused.
TEST(SynthTool, RegisterColourUndoesAnUnregisteredColourCamera) {
  const fs::path r = test::tempDir("synth_tool_colour_registered"),
                 u = test::tempDir("synth_tool_colour_unregistered"),
                 root = test::tempDir("synth_tool_colour_script");
  const std::string common = " --frames 2 --width 160 --height 120 --noise off";
  ASSERT_EQ(runTool("'" + r.string() + "'" + common), 0);
  ASSERT_EQ(runTool("'" + u.string() + "'" + common +
                    " --colour-focal-ratio 0.897 --colour-baseline 0.025"),
            0);
  const fs::path script = test::sourceDir() / "scripts" / "register_colour";
  auto registerColour = [&](const fs::path& out, const std::string& options) {
    const std::string command = "'" + script.string() + "' '" + u.string() + "' '" + out.string() +
                                "' " + options + " >/dev/null 2>&1";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  const fs::path right = root / "right", sign = root / "sign", focal = root / "focal";
  ASSERT_EQ(registerColour(right, "--focal-ratio 0.897 --baseline 0.025"), 0);
  ASSERT_EQ(registerColour(sign, "--focal-ratio 0.897 --baseline -0.025"), 0);
  ASSERT_EQ(registerColour(focal, "--focal-ratio 0.897"), 0);
  for (const std::string image : {"rgb/1000.000000.png", "rgb/1000.033333.png"}) {
    const double as_recorded = meanDifference(u / image, r / image);
    const double registered = meanDifference(right / image, r / image);
    EXPECT_GT(as_recorded, 12.0) << image;
    EXPECT_LT(registered, 3.5) << image;
    EXPECT_GT(meanDifference(focal / image, r / image), 1.5 * registered) << image;
    EXPECT_GT(meanDifference(sign / image, r / image), 2.0 * registered) << image;
    // The depth is not touched.
    const std::string depth = "depth" + image.substr(3);
    EXPECT_EQ(readBytes(right / depth), readBytes(u / depth));
  }
  EXPECT_EQ(readRows(right / "groundtruth.txt"), readRows(u / "groundtruth.txt"));
  // associations.txt depth first, as ICL-NUIM's archives list it: the same colour images.
  const fs::path depth_first = root / "depth_first_src", from_depth_first = root / "depth_first";
  fs::copy(u, depth_first, fs::copy_options::recursive);
  {
    std::ofstream out(depth_first / "associations.txt");
    for (const auto& row : readRows(u / "associations.txt")) {
      ASSERT_EQ(row.size(), 4u);
      out << row[2] << ' ' << row[3] << ' ' << row[0] << ' ' << row[1] << '\n';
    }
  }
  const std::string script_call = "'" + script.string() + "' '" + depth_first.string() + "' '" +
                                  from_depth_first.string() + "' --focal-ratio 0.897 --baseline " +
                                  "0.025 >/dev/null 2>&1";
  ASSERT_EQ(std::system(script_call.c_str()), 0);
  for (const std::string image : {"rgb/1000.000000.png", "rgb/1000.033333.png"}) {
    EXPECT_EQ(readBytes(from_depth_first / image), readBytes(right / image)) << image;
  }
  EXPECT_NE(registerColour(right, "--focal-ratio 0.897"), 0);  // exists
  EXPECT_NE(registerColour(root / "bad", "--focal-ratio 3"), 0);
  EXPECT_FALSE(fs::exists(root / "bad"));
}

// Runs scripts/NAME with `arguments`; returns its exit status.
int runScript(const std::string& name, const std::string& arguments) {
  const fs::path script = test::sourceDir() / "scripts" / name;
  const std::string command = "'" + script.string() + "' " + arguments + " >/dev/null 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Mean absolute difference of two colour images over the pixels within `radius` of the
// centre (in fractions of the half-diagonal).
double centralDifference(const cv::Mat& x, const cv::Mat& y, double radius) {
  double sum = 0.0;
  int n = 0;
  const double cx = 0.5 * (x.cols - 1), cy = 0.5 * (x.rows - 1), r = radius * std::hypot(cx, cy);
  for (int v = 0; v < x.rows; ++v) {
    for (int u = 0; u < x.cols; ++u) {
      if (std::hypot(u - cx, v - cy) > r) continue;
      const cv::Vec3b a = x.at<cv::Vec3b>(v, u), b = y.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) sum += std::abs(int(a[c]) - int(b[c]));
      n += 3;
    }
  }
  return sum / n;
}

// scripts/distort_tum puts a pinhole rendering through fr1's lens; loaded with the coefficients
// it wrote, the frames are the rendering again (measured: 0.95 grey levels inside 80% of the
// half-diagonal, the lens's resampling twice), without them 11.5; the depth likewise.
TEST(SynthTool, DistortTumIsUndoneOnLoading) {
  const fs::path pinhole = test::tempDir("synth_tool_pinhole"),
                 root = test::tempDir("synth_tool_lens");
  ASSERT_EQ(runTool("'" + pinhole.string() + "' --frames 1 --noise off"), 0);
  const std::string lens = " --coefficients 0.2624,-0.9531,-0.0054,0.0026,1.1633";
  const fs::path listed = root / "listed", unlisted = root / "unlisted";
  ASSERT_EQ(runScript("distort_tum", "'" + pinhole.string() + "' '" + listed.string() + "'" + lens),
            0);
  ASSERT_EQ(runScript("distort_tum", "'" + pinhole.string() + "' '" + unlisted.string() + "'" +
                                         lens + " --unlisted"),
            0);
  const Frame truth = TumDataset(pinhole.string()).loadFrame(0);
  const TumDataset with_lens(listed.string()), without(unlisted.string());
  EXPECT_TRUE(with_lens.distortion().any());
  EXPECT_FALSE(without.distortion().any());
  const Frame undistorted = with_lens.loadFrame(0), raw = without.loadFrame(0);
  const double d_undistorted = centralDifference(undistorted.color, truth.color, 0.8);
  const double d_raw = centralDifference(raw.color, truth.color, 0.8);
  std::printf("  mean difference to the pinhole rendering: %.2f undistorted, %.2f raw\n",
              d_undistorted, d_raw);
  EXPECT_LT(d_undistorted, 2.0);
  EXPECT_GT(d_raw, 3.0 * d_undistorted);
  // Depth: the same depth at most pixels of the centre (nearest pixels twice: edges move by one).
  int same = 0, seen = 0;
  for (int v = 120; v < 360; ++v) {
    for (int u = 160; u < 480; ++u) {
      const float a = undistorted.depth.at<float>(v, u), b = truth.depth.at<float>(v, u);
      if (!(b > 0.0f)) continue;
      ++seen;
      same += std::abs(a - b) < 1e-3f * b;
    }
  }
  EXPECT_GT(same, 0.97 * seen);
  EXPECT_NE(runScript("distort_tum", "'" + pinhole.string() + "' '" + listed.string() + "'" + lens),
            0);  // exists
  EXPECT_NE(runScript("distort_tum", "'" + pinhole.string() + "' '" + (root / "bad").string() +
                                         "' --coefficients 1,2"),
            0);
  EXPECT_FALSE(fs::exists(root / "bad"));
}

// scripts/downsample_tum: half the size, intrinsics about the blocks' centres, each depth pixel
// its block's nearest valid depth; a folder that exists or a size that does not divide refused.
TEST(SynthTool, DownsampleTumHalvesTheFolder) {
  const fs::path full = test::tempDir("synth_tool_full"), root = test::tempDir("synth_tool_half");
  ASSERT_EQ(runTool("'" + full.string() + "' --frames 1 --width 160 --height 120"), 0);
  const fs::path half = root / "half";
  ASSERT_EQ(runScript("downsample_tum", "'" + full.string() + "' '" + half.string() + "'"), 0);
  const TumDataset a(full.string()), b(half.string());
  EXPECT_EQ(b.camera().width, 80);
  EXPECT_EQ(b.camera().height, 60);
  EXPECT_DOUBLE_EQ(b.camera().fx, a.camera().fx / 2);
  EXPECT_DOUBLE_EQ(b.camera().cx, (a.camera().cx + 0.5) / 2 - 0.5);
  EXPECT_DOUBLE_EQ(b.camera().depth_scale, a.camera().depth_scale);
  const Frame fa = a.loadFrame(0), fb = b.loadFrame(0);
  for (int v = 0; v < 60; ++v) {
    for (int u = 0; u < 80; ++u) {
      float nearest = 0.0f;
      for (int dv = 0; dv < 2; ++dv) {
        for (int du = 0; du < 2; ++du) {
          const float z = fa.depth.at<float>(2 * v + dv, 2 * u + du);
          if (z > 0.0f && (nearest == 0.0f || z < nearest)) nearest = z;
        }
      }
      ASSERT_EQ(fb.depth.at<float>(v, u), nearest) << u << ", " << v;
    }
  }
  EXPECT_NE(runScript("downsample_tum", "'" + full.string() + "' '" + half.string() + "'"), 0);
  EXPECT_NE(runScript("downsample_tum",
                      "'" + full.string() + "' '" + (root / "third").string() + "' --factor 3"),
            0);  // 160 does not divide by 3
  EXPECT_FALSE(fs::exists(root / "third"));
}

// The spread of a's depth over b's, as the ratios' standard deviation over the pixels where both
// have depth: a uniform scale (which scripts/depth_distortion cannot see) does not count.
double ratioSpread(const cv::Mat& a, const cv::Mat& b) {
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (int v = 0; v < a.rows; ++v) {
    for (int u = 0; u < a.cols; ++u) {
      const float x = a.at<float>(v, u), y = b.at<float>(v, u);
      if (!(x > 0.0f) || !(y > 0.0f)) continue;
      sum += x / y;
      sum2 += (x / y) * (x / y);
      ++n;
    }
  }
  return n > 0 ? std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n))) : 0.0;
}

// scripts/depth_distortion on a rendered camera whose depth carries a fixed distortion of 2%
// (the same room and noise rendered without it is the truth): the corrected copy's depth spreads
// about the truth's by less than the distorted depth (measured: 0.0130 against 0.0204), a field
// written with --json and applied again gives the same copy, and bad calls are refused.
TEST(SynthTool, DepthDistortionFindsAFixedDistortionAndRemovesPartOfIt) {
  const fs::path root = test::tempDir("synth_tool_depth_distortion");
  const std::string common = " --frames 12 --width 160 --height 120";
  const fs::path distorted = root / "distorted", truth = root / "truth";
  ASSERT_EQ(runTool("'" + distorted.string() + "'" + common + " --depth-distortion 0.02"), 0);
  ASSERT_EQ(runTool("'" + truth.string() + "'" + common), 0);
  const fs::path fixed = root / "fixed", again = root / "again", field = root / "field.json";
  ASSERT_EQ(
      runScript("depth_distortion", "'" + distorted.string() + "' --every 1 --json '" +
                                        field.string() + "' --write '" + fixed.string() + "'"),
      0);
  const TumDataset d(distorted.string()), t(truth.string()), f(fixed.string());
  for (std::size_t i : {0, 6, 11}) {
    const cv::Mat truth_depth = t.loadFrame(i).depth;
    const double before = ratioSpread(d.loadFrame(i).depth, truth_depth);
    const double after = ratioSpread(f.loadFrame(i).depth, truth_depth);
    std::printf("  frame %zu: depth spread about the truth %.4f distorted, %.4f corrected\n", i,
                before, after);
    EXPECT_GT(before, 0.015);  // the rendering's 2%
    EXPECT_LT(after, 0.75 * before);
  }
  ASSERT_EQ(
      runScript("depth_distortion", "'" + distorted.string() + "' --apply '" + field.string() +
                                        "' --write '" + again.string() + "'"),
      0);
  const std::string image = d.frames()[6].depth.path;
  EXPECT_EQ(readBytes(again / image), readBytes(fixed / image));
  EXPECT_NE(runScript("depth_distortion",
                      "'" + distorted.string() + "' --write '" + fixed.string() + "'"),
            0);  // exists
  EXPECT_EQ(runScript("depth_distortion", "'" + distorted.string() + "' --iterations 0"), 2);
  EXPECT_EQ(runScript("depth_distortion", "'" + distorted.string() + "' --apply '" +
                                              (root / "none.json").string() + "'"),
            1);
}

TEST(SynthTool, HelpAndBadOptions) {
  EXPECT_EQ(runTool("--help"), 0);
  const std::string out = "'" + test::tempDir("synth_tool_bad").string() + "'";
  EXPECT_EQ(runTool(""), 2);                     // no output folder
  EXPECT_EQ(runTool(out + " " + out), 2);        // two output folders
  EXPECT_EQ(runTool(out + " --frames"), 2);      // missing value
  EXPECT_EQ(runTool(out + " --frames ten"), 2);  // not a number
  EXPECT_EQ(runTool(out + " --frames 0"), 2);    // out of range
  EXPECT_EQ(runTool(out + " --rate -30"), 2);
  EXPECT_EQ(runTool(out + " --speed -1"), 2);
  EXPECT_EQ(runTool(out + " --motion spiral"), 2);
  EXPECT_EQ(runTool(out + " --noise maybe"), 2);
  EXPECT_EQ(runTool(out + " --width 4"), 2);
  EXPECT_EQ(runTool(out + " --colour-focal-ratio 0.2"), 2);
  EXPECT_EQ(runTool(out + " --colour-baseline 2"), 2);
  EXPECT_EQ(runTool(out + " --colour-delay 0.02"), 2);  // over half a frame at 30 Hz
  EXPECT_EQ(runTool(out + " --brightness-swing 1"), 2);
  EXPECT_EQ(runTool(out + " --vignetting 0.5"), 2);
  EXPECT_EQ(runTool(out + " --depth-noise-correlation -1"), 2);
  EXPECT_EQ(runTool(out + " --depth-noise-correlation 60"), 2);
  EXPECT_EQ(runTool(out + " --depth-distortion -0.01"), 2);
  EXPECT_EQ(runTool(out + " --depth-distortion 0.06"), 2);
  EXPECT_EQ(runTool(out + " --walker -1"), 2);
  EXPECT_EQ(runTool(out + " --walker 1 --structure off"), 2);  // nothing to walk through
  EXPECT_EQ(runTool(out + " --colour red"), 2);                // unknown option
  EXPECT_FALSE(fs::exists(test::tempDir("synth_tool_bad") / "rgb.txt"));
  // A folder that cannot be created is a run-time failure, not a usage error.
  EXPECT_EQ(runTool("/proc/acvo_synth_cannot_write --frames 1 --width 16 --height 12"), 1);
}

}  // namespace
}  // namespace acvo::synth
