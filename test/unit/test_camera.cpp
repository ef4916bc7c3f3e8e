// Camera intrinsics: TUM names, YAML load/save, validation, projection.
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "acvo/cloud/camera.hpp"
#include "test_support.hpp"

namespace {

using acvo::Camera;

using acvo::test::errorOf;
using acvo::test::writeText;

TEST(Camera, TumNamesGiveThePublishedIntrinsics) {
  const Camera fr1 = acvo::cameraByName("fr1");
  EXPECT_DOUBLE_EQ(fr1.fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1.fy, 516.5);
  EXPECT_DOUBLE_EQ(fr1.cx, 318.6);
  EXPECT_DOUBLE_EQ(fr1.cy, 255.3);
  const Camera fr2 = acvo::cameraByName("fr2");
  EXPECT_DOUBLE_EQ(fr2.fx, 520.9);
  EXPECT_DOUBLE_EQ(fr2.cy, 249.7);
  const Camera fr3 = acvo::cameraByName("fr3");
  EXPECT_DOUBLE_EQ(fr3.fx, 535.4);
  EXPECT_DOUBLE_EQ(fr3.fy, 539.2);
  const Camera def = acvo::cameraByName("default");
  EXPECT_DOUBLE_EQ(def.fx, 525.0);
  EXPECT_DOUBLE_EQ(def.cx, 319.5);
  EXPECT_DOUBLE_EQ(def.cy, 239.5);
  for (const char* name : {"fr1", "fr2", "fr3", "default"}) {
    const Camera c = acvo::cameraByName(name);
    EXPECT_EQ(c.width, 640) << name;
    EXPECT_EQ(c.height, 480) << name;
    EXPECT_DOUBLE_EQ(c.depth_scale, 5000.0) << name;
    EXPECT_TRUE(c.valid()) << name;
  }
}

TEST(Camera, NominalIntrinsicsAreTheDefaultsNotACalibration) {
  const acvo::LensDistortion none;
  // TUM's default and 7-Scenes' (585 px about the image's centre): nominal.
  EXPECT_TRUE(acvo::nominalIntrinsics(acvo::cameraByName("default"), none));
  Camera seven_scenes;
  seven_scenes.fx = seven_scenes.fy = 585.0;
  seven_scenes.cx = 320.0;
  seven_scenes.cy = 240.0;
  EXPECT_TRUE(acvo::nominalIntrinsics(seven_scenes, none));
  // A simulator's centre at (w + 1) / 2, at another size.
  Camera simulated;
  simulated.width = 1280;
  simulated.height = 720;
  simulated.fx = simulated.fy = 1108.5;
  simulated.cx = 640.5;
  simulated.cy = 360.5;
  EXPECT_TRUE(acvo::nominalIntrinsics(simulated, none));
  // Calibrations: TUM's three, and the defaults with any one value moved.
  for (const char* name : {"fr1", "fr2", "fr3"}) {
    EXPECT_FALSE(acvo::nominalIntrinsics(acvo::cameraByName(name), none)) << name;
  }
  Camera moved = seven_scenes;
  moved.fy = 585.5;
  EXPECT_FALSE(acvo::nominalIntrinsics(moved, none));
  moved = seven_scenes;
  moved.cx = 320.3;
  EXPECT_FALSE(acvo::nominalIntrinsics(moved, none));
  moved = seven_scenes;
  moved.cy = 241.0;  // (h + 2) / 2: no convention's centre
  EXPECT_FALSE(acvo::nominalIntrinsics(moved, none));
  // A lens that was calibrated makes the intrinsics a calibration too.
  EXPECT_FALSE(acvo::nominalIntrinsics(seven_scenes, acvo::distortionByName("fr1")));
}

TEST(Camera, UnknownNameThrows) {
  EXPECT_THROW(acvo::cameraByName("fr4"), std::invalid_argument);
  EXPECT_THROW(acvo::cameraByName(""), std::invalid_argument);
}

TEST(Camera, YamlRoundTripIsExact) {
  const auto dir = acvo::test::tempDir("camera_roundtrip");
  Camera c;
  c.fx = 585.123456789012;
  c.fy = 584.9876543210987;
  c.cx = 320.1 / 3.0;
  c.cy = 239.75;
  c.width = 320;
  c.height = 240;
  c.depth_scale = 1000.0;
  acvo::saveCameraYaml((dir / "camera.yaml").string(), c);
  const Camera r = acvo::loadCameraYaml((dir / "camera.yaml").string());
  EXPECT_EQ(r.fx, c.fx);
  EXPECT_EQ(r.fy, c.fy);
  EXPECT_EQ(r.cx, c.cx);
  EXPECT_EQ(r.cy, c.cy);
  EXPECT_EQ(r.width, c.width);
  EXPECT_EQ(r.height, c.height);
  EXPECT_EQ(r.depth_scale, c.depth_scale);
}

TEST(Camera, YamlDepthScaleDefaultsToTumPng) {
  const auto dir = acvo::test::tempDir("camera_default_scale");
  writeText(dir / "c.yaml", "fx: 500\nfy: 501\ncx: 300\ncy: 200\nwidth: 600\nheight: 400\n");
  const Camera c = acvo::loadCameraYaml((dir / "c.yaml").string());
  EXPECT_DOUBLE_EQ(c.fx, 500.0);
  EXPECT_DOUBLE_EQ(c.fy, 501.0);
  EXPECT_EQ(c.width, 600);
  EXPECT_DOUBLE_EQ(c.depth_scale, 5000.0);
}

// camera_calibration's file (and OpenCV's): image_width, camera_matrix {rows, cols, data}.
TEST(Camera, YamlOfCameraCalibration) {
  const auto dir = acvo::test::tempDir("camera_calibration_yaml");
  writeText(dir / "c.yaml",
            "image_width: 848\nimage_height: 480\ncamera_name: d435\ncamera_matrix:\n  rows: 3\n"
            "  cols: 3\n  data: [421.5, 0, 424.2, 0, 422.0, 240.7, 0, 0, 1]\n"
            "distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n"
            "  data: [0, 0, 0, 0, 0]\n");
  const Camera c = acvo::loadCameraYaml((dir / "c.yaml").string());
  EXPECT_DOUBLE_EQ(c.fx, 421.5);
  EXPECT_DOUBLE_EQ(c.cx, 424.2);
  EXPECT_DOUBLE_EQ(c.fy, 422.0);
  EXPECT_DOUBLE_EQ(c.cy, 240.7);
  EXPECT_EQ(c.width, 848);
  EXPECT_EQ(c.height, 480);
  writeText(dir / "list.yaml", "camera_matrix: [421.5, 0, 424.2, 0, 422.0, 240.7, 0, 0, 1]\n");
  EXPECT_DOUBLE_EQ(acvo::loadCameraYaml((dir / "list.yaml").string()).fy, 422.0);
  writeText(dir / "short.yaml", "camera_matrix: [421.5, 0, 424.2, 0, 422.0, 240.7, 0, 0]\n");
  const std::string why = errorOf([&] { acvo::loadCameraYaml((dir / "short.yaml").string()); });
  EXPECT_NE(why.find("camera_matrix"), std::string::npos) << why;
}

// Without a size the camera is 0 x 0, for the dataset to take from its images; half a size is
// an error.
TEST(Camera, YamlWithoutTheImageSize) {
  const auto dir = acvo::test::tempDir("camera_no_size");
  writeText(dir / "c.yaml", "fx: 500\nfy: 501\ncx: 300\ncy: 200\n");
  const Camera c = acvo::loadCameraYaml((dir / "c.yaml").string());
  EXPECT_EQ(c.width, 0);
  EXPECT_EQ(c.height, 0);
  writeText(dir / "half.yaml", "fx: 500\nfy: 501\ncx: 300\ncy: 200\nwidth: 600\n");
  const std::string why = errorOf([&] { acvo::loadCameraYaml((dir / "half.yaml").string()); });
  EXPECT_NE(why.find("height"), std::string::npos) << why;
}

TEST(Camera, YamlProblemsNameTheFileAndTheKey) {
  const auto dir = acvo::test::tempDir("camera_invalid");
  const std::string missing_key = (dir / "missing.yaml").string();
  writeText(missing_key, "fx: 500\nfy: 501\ncx: 300\nwidth: 600\nheight: 400\n");
  std::string why = errorOf([&] { acvo::loadCameraYaml(missing_key); });
  EXPECT_NE(why.find(missing_key), std::string::npos) << why;
  EXPECT_NE(why.find("cy"), std::string::npos) << why;

  const std::string not_number = (dir / "text.yaml").string();
  writeText(not_number, "fx: wide\nfy: 501\ncx: 300\ncy: 200\nwidth: 600\nheight: 400\n");
  why = errorOf([&] { acvo::loadCameraYaml(not_number); });
  EXPECT_NE(why.find("fx"), std::string::npos) << why;

  const std::string zero = (dir / "zero.yaml").string();
  writeText(zero, "fx: 0\nfy: 501\ncx: 300\ncy: 200\nwidth: 600\nheight: 400\n");
  why = errorOf([&] { acvo::loadCameraYaml(zero); });
  EXPECT_NE(why.find(zero), std::string::npos) << why;
  EXPECT_NE(why.find("zero focal length"), std::string::npos) << why;

  const std::string mirrored = (dir / "mirrored.yaml").string();
  writeText(mirrored, "fx: 481.2\nfy: -480\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\n");
  EXPECT_DOUBLE_EQ(acvo::loadCameraYaml(mirrored).fy, -480.0);

  const std::string absent = (dir / "absent.yaml").string();
  why = errorOf([&] { acvo::loadCameraYaml(absent); });
  EXPECT_NE(why.find(absent), std::string::npos) << why;
}

TEST(Camera, ValidRejectsZeroNonPositiveSizesAndNonFinite) {
  Camera c;
  EXPECT_TRUE(c.valid());
  EXPECT_FALSE(c.mirrored());
  c.fy = -480.0;  // a mirrored y axis (ICL-NUIM's intrinsics)
  EXPECT_TRUE(c.valid());
  EXPECT_TRUE(c.mirrored());
  c = Camera();
  c.fx = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(c.valid());
  c = Camera();
  c.fy = 0.0;
  EXPECT_FALSE(c.valid());
  c = Camera();
  c.width = 0;
  EXPECT_FALSE(c.valid());
  c = Camera();
  c.depth_scale = -1.0;
  EXPECT_FALSE(c.valid());
}

TEST(Camera, ProjectInvertsBackProject) {
  const Camera c = acvo::cameraByName("fr1");
  const Eigen::Vector3d p = c.backProject(100.25, 400.5, 2.5);
  EXPECT_DOUBLE_EQ(p.z(), 2.5);
  EXPECT_NEAR(p.x(), (100.25 - 318.6) * 2.5 / 517.3, 1e-12);
  const Eigen::Vector2d uv = c.project(p);
  EXPECT_NEAR(uv.x(), 100.25, 1e-9);
  EXPECT_NEAR(uv.y(), 400.5, 1e-9);
}

}  // namespace
