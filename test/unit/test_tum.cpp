// TUM formats: lists, associations, trajectories, and dataset folders.
#include <cmath>
#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "acvo/tum.hpp"
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

TEST(TumDataset, DefaultCameraWithoutYaml) {
  const TinyDataset data("tum_dataset_default");
  fs::remove(data.dir / "camera.yaml");
  const acvo::TumDataset dataset(data.dir.string());
  EXPECT_DOUBLE_EQ(dataset.camera().fx, 525.0);
  EXPECT_EQ(dataset.camera().width, 640);
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
