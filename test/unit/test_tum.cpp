// TUM formats: lists, associations, trajectories, and dataset folders.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "acvo/dataset/tum.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

using acvo::test::errorOf;
using acvo::test::writeText;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

acvo::TumListEntry entry(double stamp) {
  return {std::to_string(stamp), stamp, "x.png"};
}

// ---------------------------------------------------------------------------- lists

TEST(TumList, ReadsStampsVerbatimAndSkipsCommentsAndBlankLines) {
  const auto path = acvo::test::tempDir("tum_list") / "rgb.txt";
  writeText(path,
            "# color images\n# timestamp filename\n\n"
            "1305031102.175304 rgb/1305031102.175304.png\n"
            "1305031102.2\trgb/b.png\r\n"
            "   \n"
            "1305031102.243,rgb/c.png\n");
  const auto list = acvo::readTumList(path.string());
  ASSERT_EQ(list.size(), 3u);
  EXPECT_EQ(list[0].stamp_text, "1305031102.175304");
  EXPECT_DOUBLE_EQ(list[0].stamp, 1305031102.175304);
  EXPECT_EQ(list[0].path, "rgb/1305031102.175304.png");
  EXPECT_EQ(list[1].stamp_text, "1305031102.2");
  EXPECT_EQ(list[1].path, "rgb/b.png");  // tab separated, CRLF line end
  EXPECT_EQ(list[2].path, "rgb/c.png");  // comma separated
}

TEST(TumList, MalformedLineGivesFileLineAndText) {
  const auto path = (acvo::test::tempDir("tum_list_bad") / "depth.txt").string();
  writeText(path, "# header\n1.0 depth/a.png\n2.0\n");
  std::string why = errorOf([&] { acvo::readTumList(path); });
  EXPECT_TRUE(contains(why, path + ":3")) << why;
  EXPECT_TRUE(contains(why, "'2.0'")) << why;

  writeText(path, "1.0 depth/a.png\nnoon depth/b.png\n");
  why = errorOf([&] { acvo::readTumList(path); });
  EXPECT_TRUE(contains(why, path + ":2")) << why;
  EXPECT_TRUE(contains(why, "noon")) << why;
}

TEST(TumList, MissingFileIsNamed) {
  const std::string path = "/nonexistent/acvo/rgb.txt";
  EXPECT_TRUE(contains(errorOf([&] { acvo::readTumList(path); }), path));
  EXPECT_TRUE(contains(errorOf([&] { acvo::readAssociations(path); }), path));
  EXPECT_TRUE(contains(errorOf([&] { acvo::readTrajectory(path); }), path));
}

TEST(TumList, ReadsAssociations) {
  const auto path = (acvo::test::tempDir("tum_assoc") / "associations.txt").string();
  writeText(path, "# rgb depth\n1.000000 rgb/1.png 1.004000 depth/1.png\n");
  const auto a = acvo::readAssociations(path);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].rgb.stamp_text, "1.000000");
  EXPECT_EQ(a[0].rgb.path, "rgb/1.png");
  EXPECT_DOUBLE_EQ(a[0].depth.stamp, 1.004);
  EXPECT_EQ(a[0].depth.path, "depth/1.png");

  // Depth first, as in ICL-NUIM's TUM-format archives: stamps that are frame numbers.
  writeText(path, "0 depth/0.png 0 rgb/0.png\n1 ./depth/1.png 1 rgb/1.png\n");
  const auto icl = acvo::readAssociations(path);
  ASSERT_EQ(icl.size(), 2u);
  EXPECT_EQ(icl[1].rgb.path, "rgb/1.png");
  EXPECT_EQ(icl[1].depth.path, "./depth/1.png");
  EXPECT_DOUBLE_EQ(icl[1].rgb.stamp, 1.0);
  EXPECT_EQ(icl[1].depth.stamp_text, "1");
  // Not a folder: read as listed.
  writeText(path, "1 depth.png 1 rgb/1.png\n");
  EXPECT_EQ(acvo::readAssociations(path)[0].rgb.path, "depth.png");

  writeText(path, "1.0 rgb/1.png 1.0 depth/1.png\n2.0 rgb/2.png 2.0\n");
  const std::string why = errorOf([&] { acvo::readAssociations(path); });
  EXPECT_TRUE(contains(why, path + ":2")) << why;
}

// ---------------------------------------------------------------------------- association

TEST(TumAssociate, TakesClosestPairsFirstEachEntryOnce) {
  // Depth 0.006 is 0.006 s from rgb 0.000 and 0.004 s from rgb 0.010: the greedy association
  // gives it to the closer rgb 0.010 and leaves rgb 0.000 without a pair, where pairing each rgb
  // in turn with its nearest depth would have given it to rgb 0.000.
  const auto m = acvo::associate({entry(0.000), entry(0.010)}, {entry(0.006)});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_DOUBLE_EQ(m[0].rgb.stamp, 0.010);
  EXPECT_DOUBLE_EQ(m[0].depth.stamp, 0.006);
}

TEST(TumAssociate, RespectsTheMaximumDifference) {
  const auto m = acvo::associate({entry(1.0), entry(2.0)}, {entry(1.019), entry(2.021)});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_DOUBLE_EQ(m[0].rgb.stamp, 1.0);
  EXPECT_DOUBLE_EQ(m[0].depth.stamp, 1.019);
  // A wider limit takes the second pair too.
  EXPECT_EQ(acvo::associate({entry(1.0), entry(2.0)}, {entry(1.019), entry(2.021)}, 0.03).size(),
            2u);
}

TEST(TumAssociate, ResultIsSortedByRgbStamp) {
  const auto m = acvo::associate({entry(3.0), entry(1.0), entry(2.0)},
                                 {entry(2.001), entry(1.002), entry(3.003)});
  ASSERT_EQ(m.size(), 3u);
  EXPECT_DOUBLE_EQ(m[0].rgb.stamp, 1.0);
  EXPECT_DOUBLE_EQ(m[0].depth.stamp, 1.002);
  EXPECT_DOUBLE_EQ(m[1].rgb.stamp, 2.0);
  EXPECT_DOUBLE_EQ(m[1].depth.stamp, 2.001);
  EXPECT_DOUBLE_EQ(m[2].rgb.stamp, 3.0);
  EXPECT_DOUBLE_EQ(m[2].depth.stamp, 3.003);
}

TEST(TumAssociate, MatchesTheDevelopmentDatasetLists) {
  const fs::path data = acvo::test::sharedDataDir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent";
  const fs::path dir = data / "kitchen7s_dev";
  const auto m = acvo::associate(acvo::readTumList((dir / "rgb.txt").string()),
                                 acvo::readTumList((dir / "depth.txt").string()));
  const auto expected = acvo::readAssociations((dir / "associations.txt").string());
  ASSERT_EQ(m.size(), expected.size());
  for (std::size_t k = 0; k < m.size(); ++k) {
    EXPECT_EQ(m[k].rgb.path, expected[k].rgb.path);
    EXPECT_EQ(m[k].depth.path, expected[k].depth.path);
  }
}

// ---------------------------------------------------------------------------- trajectories

TEST(TumTrajectory, ReadsSeparatorsSkipsWhatTheTumToolsSkipAndNormalises) {
  const auto path = (acvo::test::tempDir("tum_traj") / "traj.txt").string();
  writeText(path,
            "# ground truth\n"
            "1.0 1 2 3 0 0 0 2\n"         // unnormalised identity
            "2.0,4,5,6,0,0,1,1\n"         // commas; 90 degrees about z
            "3.0\t7\t8\t9\t0\t0\t0\t0\n"  // all-zero quaternion: skipped
            "4.0 1 nan 3 0 0 0 1\n"       // NaN: skipped
            "5.0 0.5 0.25 0.125 0 0 0 1\n");
  const acvo::Trajectory t = acvo::readTrajectory(path);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0].stamp_text, "1.0");
  EXPECT_TRUE(t[0].pose.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  EXPECT_EQ(t[0].pose.translation(), Eigen::Vector3d(1, 2, 3));
  EXPECT_DOUBLE_EQ(t[1].stamp, 2.0);
  const Eigen::Matrix3d rz90 = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).matrix();
  EXPECT_TRUE(t[1].pose.linear().isApprox(rz90, 1e-12)) << t[1].pose.linear();
  EXPECT_EQ(t[2].stamp_text, "5.0");
  EXPECT_EQ(t[2].pose.translation(), Eigen::Vector3d(0.5, 0.25, 0.125));
}

TEST(TumTrajectory, MalformedLineGivesFileLineAndText) {
  const auto path = (acvo::test::tempDir("tum_traj_bad") / "traj.txt").string();
  writeText(path, "# header\n1.0 1 2 3 0 0 0 1\n\n2.0 1 2 3 0 0 1\n");
  std::string why = errorOf([&] { acvo::readTrajectory(path); });
  EXPECT_TRUE(contains(why, path + ":4")) << why;
  EXPECT_TRUE(contains(why, "2.0 1 2 3 0 0 1")) << why;

  writeText(path, "1.0 1 2 3 0 0 0 1\n2.0 1 two 3 0 0 0 1\n");
  why = errorOf([&] { acvo::readTrajectory(path); });
  EXPECT_TRUE(contains(why, path + ":2")) << why;
  EXPECT_TRUE(contains(why, "two")) << why;
}

TEST(TumTrajectory, WriteThenReadIsExact) {
  acvo::Trajectory t;
  for (int k = 0; k < 20; ++k) {
    acvo::StampedPose p;
    p.stamp = 1305031102.175304 + k / 30.0;
    // Half the poses keep a verbatim stamp text, half have none (the writer makes one).
    if (k % 2 == 0) {
      p.stamp_text = "1305031102." + std::to_string(175304 + k);
      p.stamp = std::stod(p.stamp_text);
    }
    const Eigen::Vector3d axis = Eigen::Vector3d(1.0, -0.5 * k, 0.3).normalized();
    p.pose.linear() = Eigen::AngleAxisd(0.37 * k - 3.0, axis).matrix();
    p.pose.translation() = Eigen::Vector3d(k / 7.0, -k * 1e-7, 3.0 + k / 3.0);
    t.push_back(p);
  }
  const auto path = (acvo::test::tempDir("tum_traj_roundtrip") / "out.txt").string();
  acvo::writeTrajectory(path, t, "round trip");
  const acvo::Trajectory r = acvo::readTrajectory(path);
  ASSERT_EQ(r.size(), t.size());
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (!t[k].stamp_text.empty()) {
      EXPECT_EQ(r[k].stamp_text, t[k].stamp_text);
    }
    EXPECT_EQ(r[k].stamp, t[k].stamp) << k;  // also without a text: written exactly
    EXPECT_LT((r[k].pose.translation() - t[k].pose.translation()).norm(), 1e-12) << k;
    EXPECT_LT((r[k].pose.linear() - t[k].pose.linear()).norm(), 1e-12) << k;
  }
}

// ---------------------------------------------------------------------------- datasets

// A 4x3 dataset: two frames, colour (B, G, R) = (10 + k, 20, 30), depth rows of 1.0 / 1.5 m in
// TUM units (5000 per metre) and one invalid pixel.
struct TinyDataset {
  fs::path dir;
  static constexpr int kWidth = 4, kHeight = 3;

  explicit TinyDataset(const std::string& name) : dir(acvo::test::tempDir(name)) {
    fs::create_directories(dir / "rgb");
    fs::create_directories(dir / "depth");
    std::ofstream rgb(dir / "rgb.txt"), depth(dir / "depth.txt");
    rgb << "# timestamp filename\n";
    depth << "# timestamp filename\n";
    for (int k = 0; k < 2; ++k) {
      cv::Mat color(kHeight, kWidth, CV_8UC3, cv::Scalar(10 + k, 20, 30));  // B, G, R
      cv::Mat raw(kHeight, kWidth, CV_16UC1, cv::Scalar(5000));
      raw.row(1).setTo(7500);
      raw.at<std::uint16_t>(2, 3) = 0;
      const std::string stamp = k == 0 ? "10.000000" : "10.033333";
      const std::string depth_stamp = k == 0 ? "10.005000" : "10.038000";
      cv::imwrite((dir / "rgb" / (stamp + ".png")).string(), color);
      cv::imwrite((dir / "depth" / (depth_stamp + ".png")).string(), raw);
      rgb << stamp << " rgb/" << stamp << ".png\n";
      depth << depth_stamp << " depth/" << depth_stamp << ".png\n";
    }
    writeText(dir / "camera.yaml",
              "fx: 4.5\nfy: 4.5\ncx: 1.5\ncy: 1.0\nwidth: 4\nheight: 3\ndepth_scale: 5000\n");
  }
};

TEST(TumDataset, LoadsBgrColourAndDepthInMetres) {
  const TinyDataset data("tum_dataset");
  const acvo::TumDataset dataset(data.dir.string());
  EXPECT_DOUBLE_EQ(dataset.camera().fx, 4.5);  // camera.yaml picked up
  EXPECT_EQ(dataset.camera().width, 4);
  ASSERT_EQ(dataset.size(), 2u);  // associated from rgb.txt and depth.txt
  EXPECT_EQ(dataset.frames()[1].depth.stamp_text, "10.038000");
  EXPECT_FALSE(dataset.groundtruth().has_value());

  const acvo::Frame f = dataset.loadFrame(1);
  EXPECT_EQ(f.problem(), "");
  EXPECT_EQ(f.order, acvo::ColorOrder::kBgr);
  ASSERT_EQ(f.color.type(), CV_8UC3);
  EXPECT_EQ(f.color.at<cv::Vec3b>(0, 0), cv::Vec3b(11, 20, 30));
  ASSERT_EQ(f.depth.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(f.depth.at<float>(0, 0), 1.0f);
  EXPECT_FLOAT_EQ(f.depth.at<float>(1, 2), 1.5f);
  EXPECT_EQ(f.depth.at<float>(2, 3), 0.0f);
  EXPECT_DOUBLE_EQ(f.stamp, 10.033333);  // the colour stamp
  EXPECT_DOUBLE_EQ(f.depth_stamp, 10.038);
  EXPECT_THROW(dataset.loadFrame(2), std::out_of_range);
}

TEST(TumDataset, UsesAssociationsAndGroundTruthWhenPresent) {
  const TinyDataset data("tum_dataset_assoc");
  // Only the second frame, paired with the first depth image on purpose.
  writeText(data.dir / "associations.txt",
            "10.033333 rgb/10.033333.png 10.005000 depth/10.005000.png\n");
  writeText(data.dir / "groundtruth.txt", "# gt\n10.0 1 2 3 0 0 0 1\n10.1 1 2 4 0 0 0 1\n");
  const acvo::TumDataset dataset(data.dir.string());
  ASSERT_EQ(dataset.size(), 1u);
  EXPECT_EQ(dataset.frames()[0].depth.path, "depth/10.005000.png");
  ASSERT_TRUE(dataset.groundtruth().has_value());
  EXPECT_EQ(dataset.groundtruth()->size(), 2u);
}

TEST(TumDataset, CameraNameOrYamlOverridesTheFolderCamera) {
  const TinyDataset data("tum_dataset_camera");
  const acvo::TumDataset by_name(data.dir.string(), "fr1");
  EXPECT_DOUBLE_EQ(by_name.camera().fx, 517.3);
  // fr1 is 640x480: the 4x3 images no longer fit, and the error names the colour file.
  const std::string why = errorOf([&] { by_name.loadFrame(0); });
  EXPECT_TRUE(contains(why, "rgb/10.000000.png")) << why;
  EXPECT_TRUE(contains(why, "640x480")) << why;

  writeText(data.dir / "other.yaml",
            "fx: 9\nfy: 9\ncx: 1.5\ncy: 1\nwidth: 4\nheight: 3\ndepth_scale: 2500\n");
  const acvo::TumDataset by_yaml(data.dir.string(), (data.dir / "other.yaml").string());
  EXPECT_DOUBLE_EQ(by_yaml.camera().fx, 9.0);
  EXPECT_FLOAT_EQ(by_yaml.loadFrame(0).depth.at<float>(0, 0), 2.0f);  // 5000 / 2500

  EXPECT_THROW(acvo::TumDataset(data.dir.string(), "no_such_camera.yaml"), std::runtime_error);
}

TEST(TumDataset, TakesTheImageSizeFromTheImagesWhenTheCameraFileHasNone) {
  const TinyDataset data("tum_dataset_no_size");
  writeText(data.dir / "camera.yaml", "fx: 4.5\nfy: 4.5\ncx: 1.5\ncy: 1.0\n");
  const acvo::TumDataset dataset(data.dir.string());
  EXPECT_EQ(dataset.camera().width, 4);
  EXPECT_EQ(dataset.camera().height, 3);
  EXPECT_FLOAT_EQ(dataset.loadFrame(1).depth.at<float>(1, 2), 1.5f);
}

TEST(TumDataset, DefaultCameraWithoutYaml) {
  const TinyDataset data("tum_dataset_default");
  fs::remove(data.dir / "camera.yaml");
  const acvo::TumDataset dataset(data.dir.string());
  EXPECT_DOUBLE_EQ(dataset.camera().fx, 525.0);
  EXPECT_EQ(dataset.camera().width, 640);
  EXPECT_EQ(dataset.namedCamera(), "");
}

TEST(TumDataset, TheFolderNameSaysWhichTumCamera) {
  EXPECT_EQ(acvo::tumCameraOfName("rgbd_dataset_freiburg1_desk"), "fr1");
  EXPECT_EQ(acvo::tumCameraOfName("rgbd_dataset_freiburg2_pioneer_360"), "fr2");
  EXPECT_EQ(acvo::tumCameraOfName("tum_fr3_teddy200"), "fr3");
  EXPECT_EQ(acvo::tumCameraOfName("FR2-xyz"), "fr2");
  for (const char* other : {"kitchen7s_dev", "fr4_room", "fr12", "africa3", "freiburg", ""}) {
    EXPECT_EQ(acvo::tumCameraOfName(other), "") << other;
  }

  // Without camera.yaml, the named camera's calibrated intrinsics and lens (a trailing '/' too).
  const TinyDataset tiny("rgbd_dataset_freiburg1_tiny");
  fs::remove(tiny.dir / "camera.yaml");
  for (const std::string& path : {tiny.dir.string(), tiny.dir.string() + "/"}) {
    const acvo::TumDataset dataset(path);
    EXPECT_DOUBLE_EQ(dataset.camera().fx, 517.3) << path;
    EXPECT_TRUE(dataset.distortion().any()) << path;
    EXPECT_EQ(dataset.namedCamera(), "fr1") << path;
  }
  // camera.yaml, or a camera given, comes first.
  writeText(tiny.dir / "camera.yaml", "fx: 4.5\nfy: 4.5\ncx: 1.5\ncy: 1.0\nwidth: 4\nheight: 3\n");
  EXPECT_DOUBLE_EQ(acvo::TumDataset(tiny.dir.string()).camera().fx, 4.5);
  EXPECT_EQ(acvo::TumDataset(tiny.dir.string()).namedCamera(), "");
  EXPECT_DOUBLE_EQ(acvo::TumDataset(tiny.dir.string(), "fr3").camera().fx, 535.4);
}

TEST(TumDataset, BadFilesAreNamed) {
  const TinyDataset data("tum_dataset_bad");
  // Depth stored as 8 bits: wrong type.
  cv::imwrite((data.dir / "depth" / "10.005000.png").string(),
              cv::Mat(3, 4, CV_8UC1, cv::Scalar(1)));
  // Depth of the wrong size.
  cv::imwrite((data.dir / "depth" / "10.038000.png").string(),
              cv::Mat(6, 8, CV_16UC1, cv::Scalar(5000)));
  const acvo::TumDataset dataset(data.dir.string());
  std::string why = errorOf([&] { dataset.loadFrame(0); });
  EXPECT_TRUE(contains(why, "depth/10.005000.png")) << why;
  EXPECT_TRUE(contains(why, "8UC1")) << why;
  why = errorOf([&] { dataset.loadFrame(1); });
  EXPECT_TRUE(contains(why, "depth/10.038000.png")) << why;
  EXPECT_TRUE(contains(why, "8x6")) << why;

  // A colour image that is not there.
  fs::remove(data.dir / "rgb" / "10.000000.png");
  why = errorOf([&] { dataset.loadFrame(0); });
  EXPECT_TRUE(contains(why, "rgb/10.000000.png")) << why;

  // No lists at all.
  fs::remove(data.dir / "rgb.txt");
  why = errorOf([&] { acvo::TumDataset{data.dir.string()}; });
  EXPECT_TRUE(contains(why, "rgb.txt")) << why;
  why = errorOf([&] { acvo::TumDataset{(data.dir / "absent").string()}; });
  EXPECT_TRUE(contains(why, "absent")) << why;
}

TEST(LensDistortion, ReadsTheKeysOfOpenCvTumAndRos) {
  const fs::path dir = acvo::test::tempDir("tum_distortion_keys");
  const fs::path yaml = dir / "camera.yaml";
  const std::string pinhole = "fx: 500\nfy: 500\ncx: 320\ncy: 240\n";
  auto read = [&](const std::string& text) {
    writeText(yaml, pinhole + text);
    return acvo::readCameraFile(yaml.string()).distortion.coefficients;
  };
  const std::array<double, 5> expected{0.1, -0.2, 0.001, 0.002, 0.3};
  EXPECT_EQ(read("k1: 0.1\nk2: -0.2\np1: 0.001\np2: 0.002\nk3: 0.3\n"), expected);
  EXPECT_EQ(read("d0: 0.1\nd1: -0.2\nd2: 0.001\nd3: 0.002\nd4: 0.3\n"), expected);
  // camera_calibration's and OpenCV's files: a matrix with its data.
  EXPECT_EQ(read("distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n"
                 "  data: [0.1, -0.2, 0.001, 0.002, 0.3]\n"),
            expected);
  EXPECT_EQ(read("distortion_coefficients: [0.1, -0.2]\n"),
            (std::array<double, 5>{0.1, -0.2, 0.0, 0.0, 0.0}));
  EXPECT_FALSE(acvo::LensDistortion{read("")}.any());
  // The same one read gives the intrinsics.
  writeText(yaml, pinhole + "k1: 0.1\n");
  EXPECT_DOUBLE_EQ(acvo::readCameraFile(yaml.string()).camera.cx, 320.0);

  auto error = [&](const std::string& text) {
    writeText(yaml, pinhole + text);
    return errorOf([&] { acvo::readCameraFile(yaml.string()); });
  };
  std::string why = error("k1: strong\n");
  EXPECT_TRUE(contains(why, "'k1'")) << why;
  why = error("k2: .nan\n");
  EXPECT_TRUE(contains(why, "'k2'")) << why;
  why = error("distortion_coefficients: [1, 2, 3, 4, 5, 6, 7, 8]\n");
  EXPECT_TRUE(contains(why, "distortion_coefficients")) << why;

  EXPECT_TRUE(acvo::distortionByName("fr1").any());
  EXPECT_DOUBLE_EQ(acvo::distortionByName("fr2").coefficients[0], 0.2312);
  EXPECT_FALSE(acvo::distortionByName("fr3").any());
}

// A folder of raw images through a lens with fr1's distortion (about 20 px at the corners),
// rendered from a pinhole image of white squares on grey with a box of depth: loaded with the
// distortion in camera.yaml, the squares and the box come back where the pinhole camera put
// them (measured: 0.03 px, against 12 px as recorded), and the depth holds only the depths it had.
TEST(TumDataset, UndistortsALensDistortedFolder) {
  const fs::path dir = acvo::test::tempDir("tum_distorted");
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  const int w = 640, h = 480;
  const cv::Matx33d K(517.3, 0, 318.6, 0, 516.5, 255.3, 0, 0, 1);
  const acvo::LensDistortion lens = acvo::distortionByName("fr1");

  cv::Mat pinhole(h, w, CV_8UC3, cv::Scalar::all(60)), depth(h, w, CV_16UC1, cv::Scalar(5000));
  const std::vector<cv::Point2d> centres{{60, 50}, {580, 60}, {70, 420}, {570, 430}, {320, 240}};
  for (const cv::Point2d& c : centres) {
    cv::rectangle(pinhole, cv::Rect(int(c.x) - 5, int(c.y) - 5, 11, 11), cv::Scalar::all(255),
                  cv::FILLED);
  }
  depth(cv::Rect(400, 300, 120, 100)).setTo(10000);
  // The raw image at each raw pixel shows what the pinhole camera sees where that pixel's ray
  // goes: OpenCV's undistortion of the raw pixel.
  std::vector<cv::Point2f> raw_pixels, rays;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) raw_pixels.emplace_back(float(u), float(v));
  }
  cv::undistortPoints(raw_pixels, rays, K, cv::Mat(lens.coefficients), cv::noArray(), K);
  cv::Mat map(h, w, CV_32FC2, rays.data());
  cv::Mat raw_colour, raw_depth;
  cv::remap(pinhole, raw_colour, map, cv::noArray(), cv::INTER_LINEAR);
  cv::remap(depth, raw_depth, map, cv::noArray(), cv::INTER_NEAREST);
  cv::imwrite((dir / "rgb" / "1.000000.png").string(), raw_colour);
  cv::imwrite((dir / "depth" / "1.000000.png").string(), raw_depth);
  writeText(dir / "rgb.txt", "1.000000 rgb/1.000000.png\n");
  writeText(dir / "depth.txt", "1.000000 depth/1.000000.png\n");
  const std::string intrinsics =
      "width: 640\nheight: 480\nfx: 517.3\nfy: 516.5\ncx: 318.6\ncy: 255.3\n";

  // The centroid of the bright pixels within 20 px of c.
  auto centroid = [](const cv::Mat& colour, cv::Point2d c) {
    double sx = 0, sy = 0, sw = 0;
    for (int v = int(c.y) - 20; v <= int(c.y) + 20; ++v) {
      for (int u = int(c.x) - 20; u <= int(c.x) + 20; ++u) {
        const double weight = std::max(0, colour.at<cv::Vec3b>(v, u)[1] - 60);
        sx += weight * u, sy += weight * v, sw += weight;
      }
    }
    return cv::Point2d(sx / sw, sy / sw);
  };
  writeText(dir / "camera.yaml", intrinsics);
  const acvo::Frame as_recorded = acvo::TumDataset(dir.string()).loadFrame(0);
  writeText(dir / "camera.yaml",
            intrinsics + "d0: 0.2624\nd1: -0.9531\nd2: -0.0054\nd3: 0.0026\nd4: 1.1633\n");
  const acvo::TumDataset dataset(dir.string());
  ASSERT_TRUE(dataset.distortion().any());
  const acvo::Frame f = dataset.loadFrame(0);
  double worst_raw = 0.0, worst = 0.0;
  for (const cv::Point2d& c : centres) {
    worst_raw = std::max(worst_raw, cv::norm(centroid(as_recorded.color, c) - c));
    worst = std::max(worst, cv::norm(centroid(f.color, c) - c));
  }
  std::printf("  squares off by up to %.2f px as recorded, %.3f px undistorted\n", worst_raw,
              worst);
  EXPECT_GT(worst_raw, 8.0);
  EXPECT_LT(worst, 0.2);
  // The depth: the box where it was, its edges within a pixel, no depth between the two.
  EXPECT_FLOAT_EQ(f.depth.at<float>(350, 460), 2.0f);
  EXPECT_FLOAT_EQ(f.depth.at<float>(350, 396), 1.0f);
  EXPECT_FLOAT_EQ(f.depth.at<float>(350, 404), 2.0f);
  EXPECT_FLOAT_EQ(f.depth.at<float>(296, 460), 1.0f);
  EXPECT_FLOAT_EQ(f.depth.at<float>(304, 460), 2.0f);
  int other = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float z = f.depth.at<float>(v, u);
      other += z != 0.0f && z != 1.0f && z != 2.0f;
    }
  }
  EXPECT_EQ(other, 0);
}

TEST(TumDataset, LoadsTheDevelopmentDataset) {
  const fs::path data = acvo::test::sharedDataDir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent";
  const acvo::TumDataset dataset((data / "kitchen7s_dev").string());
  EXPECT_EQ(dataset.size(), 50u);
  EXPECT_DOUBLE_EQ(dataset.camera().fx, 585.0);
  ASSERT_TRUE(dataset.groundtruth().has_value());
  EXPECT_EQ(dataset.groundtruth()->size(), 50u);
  const acvo::Frame f = dataset.loadFrame(0);
  EXPECT_EQ(f.problem(), "");
  int valid = 0;
  for (int v = 0; v < f.depth.rows; ++v) {
    for (int u = 0; u < f.depth.cols; ++u) {
      const float z = f.depth.at<float>(v, u);
      if (z > 0) ++valid;
      ASSERT_TRUE(z == 0.0f || (z > 0.2f && z < 10.0f)) << "depth " << z << " at " << u << "," << v;
    }
  }
  EXPECT_GT(valid, f.depth.rows * f.depth.cols / 2);  // a Kinect frame is mostly valid
}

}  // namespace
