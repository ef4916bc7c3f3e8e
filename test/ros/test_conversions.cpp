// The nodelet's message conversions, covariance model, stamp rules, warning throttle and
// parameter loading, without a ROS master.
#include <cmath>
#include <cstring>
#include <variant>

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <gtest/gtest.h>
#include <pcl_conversions/pcl_conversions.h>
#include <sensor_msgs/image_encodings.h>

#include "cause_throttle.hpp"
#include "conversions.hpp"
#include "covariance.hpp"
#include "messages.hpp"
#include "point_types.hpp"
#include "ros_params.hpp"
#include "stamp_check.hpp"

namespace acvo_ros {
namespace {
namespace enc = sensor_msgs::image_encodings;

sensor_msgs::Image image(const std::string& encoding, int w, int h, int bytes_per_pixel) {
  sensor_msgs::Image m;
  m.encoding = encoding;
  m.width = w;
  m.height = h;
  m.step = w * bytes_per_pixel;
  m.data.assign(m.step * h, 0);
  return m;
}

sensor_msgs::CameraInfo info(double fx, double fy, double cx, double cy, int w, int h) {
  sensor_msgs::CameraInfo i;
  i.K = {fx, 0, cx, 0, fy, cy, 0, 0, 1};
  i.width = w;
  i.height = h;
  return i;
}

TEST(StripSlash, RemovesLeadingSlashesOnly) {
  EXPECT_EQ(stripSlash("/openni_rgb_optical_frame"), "openni_rgb_optical_frame");
  EXPECT_EQ(stripSlash("//a/b"), "a/b");
  EXPECT_EQ(stripSlash("odom"), "odom");
  EXPECT_EQ(stripSlash(""), "");
}

TEST(DecodeColor, KeepsChannelOrderOfEachEncoding) {
  // One pixel with R=10, G=20, B=30 in every encoding.
  struct Case {
    std::string encoding;
    std::vector<std::uint8_t> bytes;
    acvo::ColorOrder order;
    std::vector<std::uint8_t> expected;  // the decoded pixel's channels
  };
  const std::vector<Case> cases = {
      {enc::RGB8, {10, 20, 30}, acvo::ColorOrder::kRgb, {10, 20, 30}},
      {enc::BGR8, {30, 20, 10}, acvo::ColorOrder::kBgr, {30, 20, 10}},
      {enc::RGBA8, {10, 20, 30, 255}, acvo::ColorOrder::kRgb, {10, 20, 30}},
      {enc::BGRA8, {30, 20, 10, 255}, acvo::ColorOrder::kBgr, {30, 20, 10}},
      {enc::MONO8, {77}, acvo::ColorOrder::kGray, {77}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.encoding);
    sensor_msgs::Image m = image(c.encoding, 1, 1, static_cast<int>(c.bytes.size()));
    m.data = c.bytes;
    const ColorImage out = decodeColor(m);
    ASSERT_EQ(out.problem, "");
    EXPECT_EQ(out.order, c.order);
    ASSERT_EQ(out.image.channels(), static_cast<int>(c.expected.size()));
    for (std::size_t k = 0; k < c.expected.size(); ++k) {
      EXPECT_EQ(out.image.ptr<std::uint8_t>(0)[k], c.expected[k]);
    }
  }
}

TEST(DecodeColor, NamesAnUnsupportedEncoding) {
  const ColorImage out = decodeColor(image(enc::YUV422, 4, 2, 2));
  EXPECT_NE(out.problem.find("'yuv422'"), std::string::npos) << out.problem;
  EXPECT_TRUE(out.image.empty());
}

TEST(DecodeColor, RejectsTruncatedDataAndShortStep) {
  sensor_msgs::Image m = image(enc::RGB8, 4, 3, 3);
  m.data.resize(m.data.size() - 1);
  EXPECT_NE(decodeColor(m).problem.find("truncated"), std::string::npos);
  m = image(enc::RGB8, 4, 3, 3);
  m.step = 11;
  EXPECT_NE(decodeColor(m).problem.find("step 11"), std::string::npos);
  EXPECT_NE(decodeColor(image(enc::RGB8, 0, 3, 3)).problem, "");
}

TEST(DecodeColor, HonoursRowPadding) {
  sensor_msgs::Image m = image(enc::MONO8, 2, 2, 1);
  m.step = 4;
  m.data = {1, 2, 99, 99, 3, 4, 99, 99};
  const ColorImage out = decodeColor(m);
  ASSERT_EQ(out.problem, "");
  EXPECT_EQ(out.image.at<std::uint8_t>(1, 0), 3);
  EXPECT_EQ(out.image.at<std::uint8_t>(1, 1), 4);
}

// A padded row that does not end on a whole element: cv::Mat would throw ("Step must be a
// multiple of esz1"); the decoder names it instead, so that the frame goes the rejection way.
TEST(DecodeDepth, RejectsAStepThatIsNotAWholeNumberOfElements) {
  for (const auto& [encoding, bytes] :
       {std::pair{enc::TYPE_16UC1, 2}, std::pair{enc::TYPE_32FC1, 4}}) {
    sensor_msgs::Image m = image(encoding, 4, 3, bytes);
    m.step = 4 * bytes + 1;
    m.data.assign(std::size_t{m.step} * 3, 0);
    const DepthImage out = decodeDepth(m);
    EXPECT_NE(out.problem.find("not a multiple"), std::string::npos)
        << encoding << ": " << out.problem;
    EXPECT_TRUE(out.metres.empty());
    m.step = 4 * bytes + bytes;  // padding of a whole element is fine
    m.data.assign(std::size_t{m.step} * 3, 0);
    EXPECT_EQ(decodeDepth(m).problem, "") << encoding;
  }
}

TEST(DecodeDepth, MillimetresAndMetresGiveTheSameMetres) {
  sensor_msgs::Image mm = image(enc::TYPE_16UC1, 3, 1, 2);
  const std::uint16_t raw[3] = {1500, 0, 65534};  // (65535: no reading, as 0)
  std::memcpy(mm.data.data(), raw, sizeof raw);
  const DepthImage a = decodeDepth(mm);
  ASSERT_EQ(a.problem, "");
  EXPECT_DOUBLE_EQ(a.units_per_metre, 1000.0);
  EXPECT_FLOAT_EQ(a.metres.at<float>(0, 0), 1.5f);
  EXPECT_EQ(a.metres.at<float>(0, 1), 0.0f);
  EXPECT_FLOAT_EQ(a.metres.at<float>(0, 2), 65.534f);

  sensor_msgs::Image m = image(enc::TYPE_32FC1, 3, 1, 4);
  const float raw_m[3] = {1.5f, std::nanf(""), -1.0f};
  std::memcpy(m.data.data(), raw_m, sizeof raw_m);
  const DepthImage b = decodeDepth(m);
  ASSERT_EQ(b.problem, "");
  EXPECT_FLOAT_EQ(b.metres.at<float>(0, 0), 1.5f);
  EXPECT_EQ(b.metres.at<float>(0, 1), 0.0f);  // NaN is invalid
  EXPECT_EQ(b.metres.at<float>(0, 2), 0.0f);  // negative is invalid
}

TEST(DecodeDepth, NamesAnUnsupportedEncodingAndForeignByteOrder) {
  EXPECT_NE(decodeDepth(image(enc::TYPE_8UC1, 2, 2, 1)).problem.find("'8UC1'"), std::string::npos);
  sensor_msgs::Image m = image(enc::TYPE_16UC1, 2, 2, 2);
  m.is_bigendian = 1;  // this test machine is little-endian (x86 / arm64)
  EXPECT_NE(decodeDepth(m).problem.find("byte order"), std::string::npos);
}

// The four intrinsics of a camera, each exactly.
void expectIntrinsics(const acvo::Camera& c, double fx, double fy, double cx, double cy) {
  EXPECT_DOUBLE_EQ(c.fx, fx);
  EXPECT_DOUBLE_EQ(c.fy, fy);
  EXPECT_DOUBLE_EQ(c.cx, cx);
  EXPECT_DOUBLE_EQ(c.cy, cy);
}

TEST(CameraFor, UsesCameraInfoAndChecksIt) {
  const CameraResult ok = cameraFor(info(500, 510, 320, 240, 640, 480), 640, 480, {});
  ASSERT_EQ(ok.problem, "");
  expectIntrinsics(ok.camera, 500, 510, 320, 240);
  EXPECT_TRUE(ok.camera.valid());
  EXPECT_NE(cameraFor(info(0, 510, 320, 240, 640, 480), 640, 480, {}).problem.find("focal"),
            std::string::npos);
  EXPECT_NE(cameraFor(info(500, 510, 320, 240, 320, 240), 640, 480, {}).problem.find("320x240"),
            std::string::npos);
  // A mirrored y axis (ICL-NUIM's intrinsics, fy -480) is a camera, and said to be one.
  const CameraResult mirrored = cameraFor(info(481.2, -480, 319.5, 239.5, 640, 480), 640, 480, {});
  ASSERT_EQ(mirrored.problem, "");
  expectIntrinsics(mirrored.camera, 481.2, -480, 319.5, 239.5);
  EXPECT_TRUE(mirrored.camera.valid());
  EXPECT_NE(describeCamera(mirrored.camera, {}, {}).find("mirrored"), std::string::npos);
  EXPECT_EQ(describeCamera(ok.camera, {}, {}).find("mirrored"), std::string::npos);
}

// A rectified stream of a distorted camera: K describes the raw image, P the rectified one the
// node receives. Binned and ROI streams: P scaled and shifted (image_geometry's reading).
TEST(CameraFor, UsesTheProjectionMatrixWithBinningAndRegionOfInterest) {
  sensor_msgs::CameraInfo full = info(520, 525, 330, 250, 640, 480);  // the raw image's K
  full.distortion_model = "plumb_bob";
  full.D = {0.1, -0.2, 0.0, 0.0, 0.05};
  full.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  full.P = {500, 0, 320, 0, 0, 505, 240, 0, 0, 0, 1, 0};
  const CameraResult rectified = cameraFor(full, 640, 480, {});
  ASSERT_EQ(rectified.problem, "");
  expectIntrinsics(rectified.camera, 500, 505, 320, 240);

  sensor_msgs::CameraInfo binned = full;
  binned.binning_x = binned.binning_y = 2;
  const CameraResult half = cameraFor(binned, 320, 240, {});
  ASSERT_EQ(half.problem, "");
  expectIntrinsics(half.camera, 250, 252.5, 160, 120);
  EXPECT_NE(cameraFor(binned, 640, 480, {}).problem.find("320x240 after binning"),
            std::string::npos);

  sensor_msgs::CameraInfo roi = info(500, 505, 320, 240, 640, 480);  // undistorted: K = P
  roi.distortion_model = "plumb_bob";
  roi.D.assign(5, 0.0);
  roi.R = full.R;
  roi.P = full.P;
  roi.roi.x_offset = 100;
  roi.roi.y_offset = 50;
  roi.roi.width = 200;
  roi.roi.height = 100;
  const CameraResult part = cameraFor(roi, 200, 100, {});
  ASSERT_EQ(part.problem, "");
  expectIntrinsics(part.camera, 500, 505, 220, 190);
}

TEST(CameraFor, OverridesWinOverCameraInfo) {
  const sensor_msgs::CameraInfo zero = info(0, 0, 0, 0, 0, 0);  // ignored when overridden
  IntrinsicsOverride named;
  named.camera = "fr1";
  const CameraResult fr1 = cameraFor(zero, 640, 480, named);
  ASSERT_EQ(fr1.problem, "");
  EXPECT_DOUBLE_EQ(fr1.camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1.camera.cy, 255.3);
  const CameraResult half = cameraFor(zero, 320, 240, named);
  EXPECT_DOUBLE_EQ(half.camera.fx, 517.3 / 2);
  EXPECT_DOUBLE_EQ(half.camera.cy, (255.3 + 0.5) / 2 - 0.5);

  IntrinsicsOverride values;
  values.fx = 400;
  values.fy = 401;
  values.cx = 300;
  values.cy = 200;
  const CameraResult v = cameraFor(zero, 640, 480, values);
  ASSERT_EQ(v.problem, "");
  EXPECT_DOUBLE_EQ(v.camera.fy, 401);
  values.fy = -401;  // a mirrored y axis
  EXPECT_EQ(values.problem(), "");
  EXPECT_DOUBLE_EQ(cameraFor(zero, 640, 480, values).camera.fy, -401);

  IntrinsicsOverride partial;
  partial.fx = 400;
  EXPECT_NE(partial.problem(), "");
  IntrinsicsOverride unknown;
  unknown.camera = "fr9";
  EXPECT_NE(unknown.problem().find("fr9"), std::string::npos);
  IntrinsicsOverride info_name;
  info_name.camera = "info";
  EXPECT_EQ(info_name.problem(), "");
  EXPECT_FALSE(info_name.named());
}

// The intrinsics in use are said with their source; camera_info's are told nominal when they
// are a driver's defaults (7-Scenes' 585 px about the centre here), and a calibration, a lens
// or the user's own values are not.
TEST(DescribeCamera, SaysTheIntrinsicsTheirSourceAndWhetherTheyAreNominal) {
  const InputTopics topics{"/rgb", "/depth", "/camera/rgb/camera_info"};
  const sensor_msgs::CameraInfo nominal = info(585, 585, 320, 240, 640, 480);
  const CameraResult from_info = cameraFor(nominal, 640, 480, {});
  ASSERT_EQ(from_info.problem, "");
  EXPECT_EQ(describeCamera(from_info.camera, {}, topics),
            "fx 585, fy 585, cx 320, cy 240 (640x480) from camera_info on "
            "/camera/rgb/camera_info");
  EXPECT_TRUE(nominalCameraInfo(nominal, {}));

  sensor_msgs::CameraInfo distorted = nominal;
  distorted.D = {0.1, 0, 0, 0, 0};
  EXPECT_FALSE(nominalCameraInfo(distorted, {}));
  EXPECT_TRUE(distortedCameraInfo(distorted, {}));
  EXPECT_FALSE(distortedCameraInfo(nominal, {}));
  const sensor_msgs::CameraInfo calibrated = info(535.4, 539.2, 320.1, 247.6, 640, 480);
  EXPECT_FALSE(nominalCameraInfo(calibrated, {}));

  // A binned stream and a region of interest of a nominal camera: the intrinsics in use are
  // reduced (TUM's default cx 319.5 is 159.75 with 2x2 binning, none of the 320x240 image's
  // centres) and still nominal; P, where it is filled, is what is judged.
  sensor_msgs::CameraInfo binned = info(525, 525, 319.5, 239.5, 640, 480);
  EXPECT_TRUE(nominalCameraInfo(binned, {}));
  binned.binning_x = binned.binning_y = 2;
  const CameraResult reduced = cameraFor(binned, 320, 240, {});
  ASSERT_EQ(reduced.problem, "");
  EXPECT_DOUBLE_EQ(reduced.camera.cx, 159.75);
  EXPECT_FALSE(acvo::nominalIntrinsics(reduced.camera, acvo::LensDistortion{}));
  EXPECT_TRUE(nominalCameraInfo(binned, {}));
  sensor_msgs::CameraInfo cropped = nominal;
  cropped.roi.x_offset = 100;
  cropped.roi.width = 320;
  cropped.roi.height = 480;
  ASSERT_EQ(cameraFor(cropped, 320, 480, {}).problem, "");
  EXPECT_TRUE(nominalCameraInfo(cropped, {}));
  sensor_msgs::CameraInfo projected = calibrated;
  projected.P = {585, 0, 320, 0, 0, 585, 240, 0, 0, 0, 1, 0};
  EXPECT_TRUE(nominalCameraInfo(projected, {})) << "P, not K, is in use";
  projected.P[2] = 320.6;
  EXPECT_FALSE(nominalCameraInfo(projected, {}));

  IntrinsicsOverride named;
  named.camera = "default";
  const CameraResult tum_default = cameraFor(nominal, 640, 480, named);
  EXPECT_EQ(describeCamera(tum_default.camera, named, topics),
            "fx 525, fy 525, cx 319.5, cy 239.5 (640x480) from the parameter camera: default");
  EXPECT_FALSE(nominalCameraInfo(nominal, named)) << "the user's choice";
  EXPECT_FALSE(distortedCameraInfo(distorted, named)) << "camera_info's D not in use";
  IntrinsicsOverride values;
  values.fx = values.fy = 585;
  values.cx = 320;
  values.cy = 240;
  const CameraResult given = cameraFor(nominal, 640, 480, values);
  EXPECT_EQ(describeCamera(given.camera, values, topics),
            "fx 585, fy 585, cx 320, cy 240 (640x480) from the parameters fx, fy, cx, cy");
  EXPECT_FALSE(nominalCameraInfo(nominal, values));
}

// Drivers publish the calibration's D with their rectified images too: a non-zero D is warned
// about only where the colour topic is not a rectified one by its name, and the warning says how
// to tell.
TEST(DescribeCamera, DistortionIsWarnedAboutOnlyOnAnUnrectifiedTopic) {
  sensor_msgs::CameraInfo distorted = info(585, 585, 320, 240, 640, 480);
  distorted.D = {0.1, -0.2, 0, 0, 0.05};
  const InputTopics raw{"/camera/color/image_raw", "/d", "/camera/color/camera_info"};
  const std::string warning = unrectifiedWarning(distorted, {}, raw);
  EXPECT_NE(warning.find("/camera/color/camera_info"), std::string::npos) << warning;
  EXPECT_NE(warning.find("/camera/color/image_raw is not a rectified one"), std::string::npos)
      << warning;
  EXPECT_NE(warning.find("\"rect\""), std::string::npos) << warning;
  EXPECT_NE(warning.find("image_rect_color"), std::string::npos) << warning;
  for (const char* rectified : {"/camera/rgb/image_rect_color", "/camera/rgb/image_rect",
                                "image_rect_raw"}) {
    EXPECT_EQ(unrectifiedWarning(distorted, {}, {rectified, "/d", "/i"}), "") << rectified;
  }
  // "rect" in a namespace is not the image's name (nor "direct" one's).
  EXPECT_NE(unrectifiedWarning(distorted, {}, {"/rect/image_raw", "/d", "/i"}), "");
  EXPECT_NE(unrectifiedWarning(distorted, {}, {"/camera/direct", "/d", "/i"}), "");
  EXPECT_EQ(unrectifiedWarning(info(585, 585, 320, 240, 640, 480), {}, raw), "") << "D all zero";
  IntrinsicsOverride named;
  named.camera = "fr1";
  EXPECT_EQ(unrectifiedWarning(distorted, named, raw), "") << "camera_info's D not in use";
}

Eigen::Isometry3d pose(double rx, double ry, double rz, double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(rz, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(ry, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rx, Eigen::Vector3d::UnitX()))
                   .matrix();
  t.translation() << x, y, z;
  return t;
}

TEST(FrameFromMessages, GivesTheFrameOrSaysWhyNotNamingTheTopic) {
  const InputTopics topics{"/cam/rgb", "/cam/depth", "/cam/info"};
  sensor_msgs::Image rgb = image(enc::RGB8, 4, 3, 3);
  rgb.header.frame_id = "/cam_optical";
  rgb.header.stamp = ros::Time(12, 500000000);
  sensor_msgs::Image depth = image(enc::TYPE_16UC1, 4, 3, 2);
  depth.header.stamp = ros::Time(12, 488000000);  // unsynchronised streams: its own stamp
  const sensor_msgs::CameraInfo good_info = info(3, 3, 2, 1.5, 4, 3);
  const auto ok = frameFromMessages(rgb, depth, good_info, {}, topics);
  ASSERT_TRUE(std::holds_alternative<acvo::Frame>(ok)) << std::get<Rejection>(ok).why;
  const acvo::Frame& f = std::get<acvo::Frame>(ok);
  EXPECT_EQ(f.stamp, 12.5);
  EXPECT_DOUBLE_EQ(f.depth_stamp, 12.488);
  EXPECT_EQ(f.order, acvo::ColorOrder::kRgb);
  EXPECT_EQ(f.camera.fx, 3.0);

  auto why = [&](const sensor_msgs::Image& c, const sensor_msgs::Image& d,
                 const sensor_msgs::CameraInfo& i) {
    const auto r = frameFromMessages(c, d, i, {}, topics);
    return std::holds_alternative<Rejection>(r) ? std::get<Rejection>(r).why : std::string();
  };
  sensor_msgs::Image no_frame = rgb;
  no_frame.header.frame_id = "/";
  EXPECT_NE(why(no_frame, depth, good_info).find("no frame_id"), std::string::npos);
  sensor_msgs::Image bayer = rgb;
  bayer.encoding = "bayer_rggb8";
  EXPECT_NE(why(bayer, depth, good_info).find("/cam/rgb"), std::string::npos);
  sensor_msgs::Image mono16x = depth;
  mono16x.encoding = "8UC1";
  EXPECT_NE(why(rgb, mono16x, good_info).find("/cam/depth"), std::string::npos);
  const sensor_msgs::Image small = image(enc::TYPE_16UC1, 2, 3, 2);
  EXPECT_NE(why(rgb, small, good_info).find("differ in size"), std::string::npos);
  EXPECT_NE(why(rgb, depth, info(0, 3, 2, 1.5, 4, 3)).find("/cam/info"), std::string::npos);
}

TEST(Conjugate, OpticalForwardIsBaseForward) {
  // REP 103 optical frame in a base frame: z_optical = x_base, x_optical = -y_base.
  Eigen::Isometry3d base_from_optical = Eigen::Isometry3d::Identity();
  base_from_optical.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  base_from_optical.translation() << 0.1, 0.0, 0.3;
  Eigen::Isometry3d forward = Eigen::Isometry3d::Identity();
  forward.translation() << 0, 0, 1;  // 1 m along the optical axis
  const Eigen::Isometry3d base_motion = conjugate(base_from_optical, forward);
  EXPECT_TRUE(base_motion.translation().isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  EXPECT_TRUE(base_motion.rotation().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  // A yaw of the camera about its own y (down) axis is a yaw of the base about -z.
  const Eigen::Isometry3d yaw = conjugate(base_from_optical, pose(0, 0.1, 0, 0, 0, 0));
  EXPECT_NEAR(Eigen::AngleAxisd(yaw.rotation()).angle(), 0.1, 1e-12);
  EXPECT_TRUE(Eigen::AngleAxisd(yaw.rotation()).axis().isApprox(Eigen::Vector3d(0, 0, -1), 1e-9));
}

TEST(TwistOf, IsMotionOverTime) {
  const Twist t = twistOf(pose(0, 0, 0.2, 0.3, 0, 0), 0.1);
  EXPECT_TRUE(t.linear.isApprox(Eigen::Vector3d(3, 0, 0), 1e-12));
  EXPECT_TRUE(t.angular.isApprox(Eigen::Vector3d(0, 0, 2), 1e-12));
  EXPECT_TRUE(twistOf(pose(0, 0, 0.2, 0.3, 0, 0), 0.0).linear.isZero());
}

TEST(PoseMsg, RoundTripsAndRejectsZeroQuaternion) {
  const Eigen::Isometry3d p = pose(0.1, -0.2, 0.3, 1, 2, 3);
  std::string problem = "stale";
  EXPECT_TRUE(fromPoseMsg(toPoseMsg(p), &problem).isApprox(p, 1e-12));
  EXPECT_EQ(problem, "");
  geometry_msgs::Pose zero;
  fromPoseMsg(zero, &problem);
  EXPECT_NE(problem, "");
}

// The published cloud read back as a PCL user reads it: every channel through acvo's own
// point type, the colour through pcl::PointXYZRGB (what rviz and most PCL code use).
TEST(PointCloud2, ReadsBackThroughPclWithItsLabels) {
  acvo::LabelledCloud cloud;
  cloud.points = {{1.f, 2.f, 3.f}, {-1.f, 0.5f, 4.f}};
  cloud.rgb = {{{255, 128, 1}}, {{0, 0, 0}}};
  acvo::Label l0, l1;
  l0 << 0.1f, 0.2f, 0.3f, -0.4f, 0.5f;
  l1 << 0.9f, 0.8f, 0.7f, 0.6f, -0.5f;
  cloud.labels = {l0, l1};
  std_msgs::Header h;
  h.frame_id = "cam";
  h.stamp = ros::Time(1305031102, 175304000);
  const sensor_msgs::PointCloud2 msg = toPointCloud2(cloud, h);
  EXPECT_EQ(msg.header.frame_id, "cam");
  EXPECT_EQ(msg.header.stamp, h.stamp) << "the stamp keeps its nanoseconds";
  EXPECT_EQ(msg.width, 2u);
  EXPECT_EQ(msg.height, 1u);
  std::vector<std::string> names;
  for (const auto& f : msg.fields) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "rgb", "hue", "saturation", "value",
                                             "gradient_x", "gradient_y"}));
  pcl::PointCloud<LabelledPoint> back;
  pcl::fromROSMsg(msg, back);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].x, -1.f);
  EXPECT_EQ(back[1].z, 4.f);
  EXPECT_EQ(back[0].r, 255);
  EXPECT_EQ(back[0].g, 128);
  EXPECT_EQ(back[0].b, 1);
  for (int i = 0; i < 2; ++i) {
    const acvo::Label& l = cloud.labels[std::size_t(i)];
    EXPECT_EQ(back[i].hue, l[0]);
    EXPECT_EQ(back[i].saturation, l[1]);
    EXPECT_EQ(back[i].value, l[2]);
    EXPECT_EQ(back[i].gradient_x, l[3]);
    EXPECT_EQ(back[i].gradient_y, l[4]);
  }
  pcl::PointCloud<pcl::PointXYZRGB> rgb;
  pcl::fromROSMsg(msg, rgb);
  ASSERT_EQ(rgb.size(), 2u);
  EXPECT_EQ(rgb[0].y, 2.f);
  EXPECT_EQ(rgb[0].getRGBVector3i(), Eigen::Vector3i(255, 128, 1));
}

TEST(Covariance, ReordersRotationFirstToRosOrder) {
  Covariance6 c = Covariance6::Zero();
  c.diagonal() << 1, 2, 3, 4, 5, 6;  // rotation x y z, translation x y z
  c(0, 3) = c(3, 0) = 0.5;           // rot x with trans x
  const Covariance6 ros = toRosOrder(c);
  Eigen::Matrix<double, 6, 1> expected;
  expected << 4, 5, 6, 1, 2, 3;
  EXPECT_TRUE(ros.diagonal().isApprox(expected));
  EXPECT_EQ(ros(3, 0), 0.5);
}

TEST(StampCheck, DropsRepeatsRestartsOnJumpBackWarnsOnGaps) {
  EXPECT_EQ(checkStamp(0.0, 100.0, 1.0), StampVerdict::kAccept);
  EXPECT_EQ(checkStamp(100.0, 100.033, 1.0), StampVerdict::kAccept);
  EXPECT_EQ(checkStamp(100.0, 100.0, 1.0), StampVerdict::kDrop);
  EXPECT_EQ(checkStamp(100.0, 99.5, 1.0), StampVerdict::kDrop);
  EXPECT_EQ(checkStamp(100.0, 98.0, 1.0), StampVerdict::kRestart);
  EXPECT_EQ(checkStamp(100.0, 101.5, 1.0), StampVerdict::kGap);
  EXPECT_EQ(checkStamp(100.0, 101.5, 2.0), StampVerdict::kAccept);
}

// A bag of 0.5 s looped at 10 Hz: its stamps go back by 0.4 s at each loop. Before, every
// frame of the second loop was dropped (behind the last processed one, by less than the 1 s
// that marks a restart), and so was every later loop: the node stalled for ever.
TEST(StampGuard, AShortLoopedBagRestartsInsteadOfStalling) {
  StampGuard guard;
  const auto feed = [&](double stamp) {
    const StampVerdict v = guard.check(stamp, 1.0, 1.0);
    if (v != StampVerdict::kDrop) guard.processed(stamp);
    return v;
  };
  for (double t : {100.0, 100.1, 100.2, 100.3, 100.4}) EXPECT_EQ(feed(t), StampVerdict::kAccept);
  EXPECT_EQ(feed(100.0), StampVerdict::kDrop) << "one frame behind: out of order, perhaps";
  EXPECT_EQ(feed(100.1), StampVerdict::kRestart) << "a second one, later: the bag looped";
  EXPECT_EQ(feed(100.2), StampVerdict::kAccept);
  EXPECT_EQ(guard.last(), 100.2);
}

TEST(StampGuard, OneFrameOutOfOrderOrRepeatedIsDroppedAndTheStreamGoesOn) {
  StampGuard guard;
  const auto feed = [&](double stamp) {
    const StampVerdict v = guard.check(stamp, 1.0, 1.0);
    if (v != StampVerdict::kDrop) guard.processed(stamp);
    return v;
  };
  EXPECT_EQ(feed(100.0), StampVerdict::kAccept);
  EXPECT_EQ(feed(100.2), StampVerdict::kAccept);
  EXPECT_EQ(feed(100.1), StampVerdict::kDrop);
  EXPECT_EQ(feed(100.3), StampVerdict::kAccept);
  // The same stamp over and over is never a restart.
  EXPECT_EQ(feed(100.3), StampVerdict::kDrop);
  EXPECT_EQ(feed(100.3), StampVerdict::kDrop);
  EXPECT_EQ(feed(100.3), StampVerdict::kDrop);
  // Two frames behind, the second earlier than the first: still out of order.
  EXPECT_EQ(feed(100.25), StampVerdict::kDrop);
  EXPECT_EQ(feed(100.22), StampVerdict::kDrop);
  EXPECT_EQ(feed(100.4), StampVerdict::kAccept);
  EXPECT_EQ(feed(97.0), StampVerdict::kRestart) << "more than 1 s back at once";
  guard.clear();
  EXPECT_EQ(guard.check(50.0, 1.0, 1.0), StampVerdict::kAccept);
}

TEST(CauseThrottle, OneSlotPerCauseSoAFrequentCauseHidesNoOther) {
  const std::string truncated_a = "truncated data: 1000 bytes for 480 rows of step 1920";
  const std::string truncated_b = "truncated data: 460800 bytes for 480 rows of step 1920";
  const std::string focal = "camera_info K has a zero focal length (fx 0, fy 0)";
  EXPECT_EQ(causeOf(truncated_a), "truncated data: # bytes for # rows of step #");
  EXPECT_EQ(causeOf(truncated_a), causeOf(truncated_b));
  EXPECT_NE(causeOf(truncated_a), causeOf(focal));

  CauseThrottle throttle(5.0);
  EXPECT_TRUE(throttle.allow(truncated_a, 100.0));
  EXPECT_FALSE(throttle.allow(truncated_b, 101.0));  // same cause within the period
  EXPECT_TRUE(throttle.allow(focal, 101.5));         // another cause is told at once
  EXPECT_FALSE(throttle.allow(focal, 106.0));
  EXPECT_TRUE(throttle.allow(truncated_b, 105.0));  // the period since 100 is over
  EXPECT_FALSE(throttle.allow(truncated_a, 109.9));
  EXPECT_TRUE(throttle.allow(focal, 106.5));
}

TEST(CauseThrottle, CausesBeyondTheLimitShareOneSlot) {
  CauseThrottle throttle(5.0, 2);
  EXPECT_TRUE(throttle.allow("unsupported encoding 'aaa'", 0.0));
  EXPECT_TRUE(throttle.allow("unsupported encoding 'bbb'", 0.0));
  // Names from the input must not grow the table: the third and fourth cause share a slot.
  EXPECT_TRUE(throttle.allow("unsupported encoding 'ccc'", 0.0));
  EXPECT_FALSE(throttle.allow("unsupported encoding 'ddd'", 1.0));
  EXPECT_TRUE(throttle.allow("unsupported encoding 'ddd'", 6.0));
  EXPECT_FALSE(throttle.allow("unsupported encoding 'aaa'", 4.0));  // its own slot still counts
}

XmlRpc::XmlRpcValue section(const std::string& key, const XmlRpc::XmlRpcValue& value) {
  XmlRpc::XmlRpcValue s;
  s[key] = value;
  return s;
}

TEST(RosParams, ReadsEverySectionWithCoreNamesAndReportsProblems) {
  XmlRpc::XmlRpcValue ns;
  ns["selection"] = section("target_points", 1234);
  ns["selection"]["max_depth"] = 4;  // an integer is fine for a double
  ns["registration"] = section("engine", std::string(acvo::toString(acvo::Engine::kPaper)));
  ns["paper"] =
      section("ell_policy", std::string(acvo::toString(acvo::EllPolicy::kFixedSchedule)));
  ns["paper"]["max_iterations"] = 2.5;  // wrong type: reported, default kept
  ns["coarse_to_fine"] = section("no_such_key", 1);
  ns["odometry"] = section("initial_guess", std::string("sideways"));
  ns["approx_sync"] = true;  // a nodelet setting, not an algorithm parameter
  ns["solver"] = section("ell_min", 0.01);  // the section before the engines were split
  acvo::Params p;
  const std::vector<std::string> problems = applyRosParams(ns, p);
  EXPECT_EQ(p.selection.target_points, 1234);
  EXPECT_DOUBLE_EQ(p.selection.max_depth, 4.0);
  EXPECT_EQ(p.registration.engine, acvo::Engine::kPaper);
  EXPECT_EQ(p.paper.ell_policy, acvo::EllPolicy::kFixedSchedule);
  EXPECT_EQ(p.paper.max_iterations, acvo::Params().paper.max_iterations);
  EXPECT_EQ(p.odometry.initial_guess, acvo::Params().odometry.initial_guess);
  ASSERT_EQ(problems.size(), 4u);
  std::string all;
  for (const auto& s : problems) all += s + "\n";
  EXPECT_NE(all.find("~paper/max_iterations"), std::string::npos) << all;
  EXPECT_NE(all.find("~odometry/initial_guess"), std::string::npos) << all;
  EXPECT_NE(all.find("~coarse_to_fine/no_such_key"), std::string::npos) << all;
  EXPECT_NE(all.find("~solver was split"), std::string::npos) << all;
}

// Before, one value that acvo::validate rejected put every parameter back to its default.
TEST(RosParams, ABadValueIsRejectedAloneAndAPairIsAcceptedInAnyOrder) {
  XmlRpc::XmlRpcValue ns;
  ns["selection"] = section("target_points", 900);
  ns["selection"]["min_depth"] = 12.0;  // above max_depth: rejected alone
  // ell_min above the default ell_init (0.04) is valid only with the raised ell_init: visited
  // first, it is accepted once ell_init is in.
  ns["coarse_to_fine"] = section("ell_min", 0.05);
  ns["coarse_to_fine"]["ell_init"] = 0.08;
  ns["coarse_to_fine"]["depth_noise"] = -1.0;  // negative: rejected alone
  acvo::Params p;
  const std::vector<std::string> problems = applyRosParams(ns, p);
  EXPECT_EQ(acvo::validate(p), "");
  EXPECT_EQ(p.selection.target_points, 900);
  EXPECT_DOUBLE_EQ(p.selection.min_depth, acvo::Params().selection.min_depth);
  EXPECT_DOUBLE_EQ(p.coarse_to_fine.ell_min, 0.05);
  EXPECT_DOUBLE_EQ(p.coarse_to_fine.ell_init, 0.08);
  EXPECT_DOUBLE_EQ(p.coarse_to_fine.depth_noise, acvo::Params().coarse_to_fine.depth_noise);
  ASSERT_EQ(problems.size(), 2u);
  EXPECT_NE(problems[0].find("~selection/min_depth rejected (selection.min_depth must be below "
                             "max_depth)"),
            std::string::npos)
      << problems[0];
  EXPECT_NE(problems[1].find("~coarse_to_fine/depth_noise rejected"), std::string::npos)
      << problems[1];
}

TEST(RosParams, UnknownNamesAreReportedWithTheNameTheyHaveHere) {
  XmlRpc::XmlRpcValue ns;
  ns["frame_id"] = std::string("base_footprint");
  ns["wait_for_transform"] = 0.5;
  ns["odom_frame"] = std::string("odom");
  ns["rgb"] = section("image_transport", std::string("compressed"));
  ns["Odom"] = section("Strategy", 0);
  ns["completely_unrelated_thing"] = 1;
  ns["base_frame_id"] = std::string("base_link");  // known
  ns["target_points"] = 1500;                       // dynamic_reconfigure's, known
  ns["selection"] = section("target_pionts", 1500);
  const std::vector<std::string> top = unknownParameters(ns, {"target_points"});
  std::string all;
  for (const auto& s : top) all += s + "\n";
  ASSERT_EQ(top.size(), 6u) << all;
  EXPECT_NE(all.find("~frame_id (ignored): this node calls it ~base_frame_id"), std::string::npos)
      << all;
  EXPECT_NE(all.find("this node calls it ~wait_for_transform_duration"), std::string::npos) << all;
  EXPECT_NE(all.find("~odom_frame (ignored) (did you mean ~odom_frame_id?)"), std::string::npos)
      << all;
  EXPECT_NE(all.find("~rgb/image_transport (ignored): this node calls it ~image_transport"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("~Odom/Strategy (ignored): rtabmap's"), std::string::npos) << all;
  EXPECT_NE(all.find("~completely_unrelated_thing (ignored)\n"), std::string::npos) << all;
  acvo::Params p;
  const std::vector<std::string> in_section = applyRosParams(ns, p);
  ASSERT_EQ(in_section.size(), 1u);
  EXPECT_NE(in_section[0].find("(did you mean ~selection/target_points?)"), std::string::npos)
      << in_section[0];
}

// dynparam shows `target_points`; the parameter is `~selection/target_points`. A private
// parameter set under a reconfigure name or a key without its section is read by nothing (and
// the reconfigure server starts from the sectioned one): it is warned about, naming the
// parameter. One whose value is the one in use is the server's own (it writes its names into
// the private namespace) and is not.
TEST(RosParams, ASectionlessNameIsWarnedAboutNamingItsSection) {
  acvo::Params in_use;
  in_use.selection.target_points = 3000;
  XmlRpc::XmlRpcValue ns;
  ns["target_points"] = 999;          // reconfigure name, another value: the trap
  ns["max_depth"] = in_use.selection.max_depth;  // reconfigure name, the value in use
  ns["paper_ell_init"] = 0.5;         // the paper engine's reconfigure name
  ns["threads"] = 2;                  // a key without its section, not reconfigurable
  ns["ell_min"] = std::string("x");   // two sections have it; reconfigure name of one
  ns["engine"] = std::string(acvo::toString(in_use.registration.engine));  // the server's
  ns["selection"] = section("target_points", 3000);
  ns["base_frame_id"] = std::string("base_link");  // a nodelet setting: not this check's
  const std::vector<std::string> problems = sectionlessParameters(ns, in_use);
  std::string all;
  for (const auto& s : problems) all += s + "\n";
  ASSERT_EQ(problems.size(), 4u) << all;
  EXPECT_NE(all.find("~ell_min = 'x' is not read (ignored): the parameter is "
                     "~coarse_to_fine/ell_min or ~paper/ell_min; dynamic_reconfigure shows "
                     "~coarse_to_fine/ell_min as ell_min"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("~paper_ell_init = 0.5 is not read (ignored): the parameter is "
                     "~paper/ell_init; dynamic_reconfigure shows ~paper/ell_init as "
                     "paper_ell_init and starts it from ~paper/ell_init, not from "
                     "~paper_ell_init\n"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("~target_points = 999 is not read (ignored): the parameter is "
                     "~selection/target_points; dynamic_reconfigure shows"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("~threads = 2 is not read (ignored): the parameter is ~odometry/threads\n"),
            std::string::npos)
      << all;
  // None of them is unknown to the check of the top-level names.
  const std::vector<std::string> unknown = unknownParameters(ns, sectionlessNames());
  EXPECT_TRUE(unknown.empty()) << unknown.front();
}

TEST(RosParams, ReconfigureRoundTripsAndDescribesEveryParameter) {
  acvo::Params p;
  p.selection.target_points = 777;
  p.registration.engine = acvo::Engine::kPaper;
  p.paper.ell_policy = acvo::EllPolicy::kFixedSchedule;
  p.paper.color_ell = 0.25;
  p.coarse_to_fine.depth_noise = 0.001;
  p.coarse_to_fine.point_to_plane = false;
  p.coarse_to_fine.photometric_vignetting = false;
  p.coarse_to_fine.exposure_time = 0.004;
  p.odometry.sync_depth = acvo::SyncDepth::kLastMotion;
  p.odometry.initial_guess = acvo::InitialGuess::kIdentity;
  const acvo::AcvoConfig c = toConfig(p, LostOdom::kNone);
  EXPECT_EQ(c.lost_odom, "none");
  const acvo::Params back = fromConfig(c, acvo::Params());
  EXPECT_EQ(describeParams(back), describeParams(p));
  EXPECT_NE(describeParams(p).find("selection/target_points=777"), std::string::npos);
  int count = 0;
  acvo::Params q;
  acvo::visitParams(q, [&](const std::string&, const std::string&, auto&) { ++count; });
  const std::string d = describeParams(q);
  EXPECT_EQ(std::count(d.begin(), d.end(), '='), count);
}

TEST(RosParams, EveryReconfigureOptionNamesAParameter) {
  EXPECT_EQ(reconfigureNamesWithoutParameter(), std::vector<std::string>{});
  // The paper section's by their prefix, the others by their key alone.
  acvo::Params p;
  p.paper.max_iterations = 77;
  p.coarse_to_fine.level_iterations = 5;
  const acvo::AcvoConfig c = toConfig(p, LostOdom::kHeld);
  EXPECT_EQ(c.paper_max_iterations, 77);
  EXPECT_EQ(c.level_iterations, 5);
}

TEST(RosParams, ReconfigureDefaultsAreTheCoreDefaults) {
  // rqt_reconfigure shows the .cfg defaults as "default": they must be acvo::Params'.
  const acvo::Params defaults;
  const acvo::Params from_cfg = fromConfig(acvo::AcvoConfig::__getDefault__(), defaults);
  EXPECT_EQ(describeParams(from_cfg), describeParams(defaults));
  EXPECT_EQ(acvo::AcvoConfig::__getDefault__().lost_odom, toString(NodeletSettings().lost_odom));
}

TEST(RosParams, EveryReconfigureEnumValueIsAcceptedByTheCore) {
  // The .cfg lists the enum strings; they must be the core's own spellings.
  for (const auto& v : {acvo::EllPolicy::kAdaptive, acvo::EllPolicy::kFixedSchedule}) {
    acvo::AcvoConfig c = toConfig(acvo::Params(), LostOdom::kHeld);
    c.paper_ell_policy = acvo::toString(v);
    EXPECT_EQ(fromConfig(c, acvo::Params()).paper.ell_policy, v);
  }
  for (const auto& v : {acvo::Engine::kCoarseToFine, acvo::Engine::kPaper}) {
    acvo::AcvoConfig c = toConfig(acvo::Params(), LostOdom::kHeld);
    c.engine = acvo::toString(v);
    EXPECT_EQ(fromConfig(c, acvo::Params()).registration.engine, v);
  }
  acvo::AcvoConfig c = acvo::AcvoConfig::__getDefault__();
  EXPECT_NO_THROW(fromConfig(c, acvo::Params()));
  for (const char* name : {"adaptive", "fixed_schedule"}) {
    acvo::EllPolicy v{};
    EXPECT_NO_THROW(acvo::fromString(name, v)) << name;
  }
  for (const char* name : {"constant_velocity", "identity"}) {
    acvo::InitialGuess v{};
    EXPECT_NO_THROW(acvo::fromString(name, v)) << name;
  }
  for (const char* name : {"held", "null", "none"}) {
    LostOdom v{};
    EXPECT_NO_THROW(fromString(name, v)) << name;
    EXPECT_EQ(toString(v), name);
  }
}

acvo::OdometryResult registered(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& motion) {
  acvo::OdometryResult r;
  r.tracking = acvo::Tracking::kOk;
  r.pose = pose;
  r.motion = motion;
  r.motion_covariance = Covariance6::Identity() * 1e-6;
  r.motion_covariance(0, 0) = 4e-6;  // rotation about the camera's x
  r.interval = 0.1;
  return r;
}

TEST(OdometryMsg, PoseTwistAndCovariancesAreInTheBaseFrame) {
  Eigen::Isometry3d base_from_optical = Eigen::Isometry3d::Identity();
  base_from_optical.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // REP 103 optical frame
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translation() << 0, 0, 0.02;  // 2 cm along the optical axis
  std_msgs::Header h;
  h.frame_id = "odom";
  acvo::OdometryResult r = registered(step, step);
  r.pose_covariance = Covariance6::Zero();
  r.pose_covariance(3, 3) = 1e-4;  // along the first camera's x (the base's -y); rotation first
  const nav_msgs::Odometry m = toOdometryMsg(r, base_from_optical, h, "base_link");
  EXPECT_EQ(m.header.frame_id, "odom");
  EXPECT_EQ(m.child_frame_id, "base_link");
  EXPECT_NEAR(m.pose.pose.position.x, 0.02, 1e-12);  // forward is the base's x
  EXPECT_NEAR(m.pose.pose.position.y, 0.0, 1e-12);
  EXPECT_NEAR(m.twist.twist.linear.x, 0.2, 1e-12);
  EXPECT_NEAR(m.pose.covariance[7], 1e-4, 1e-15);  // y y
  EXPECT_NEAR(m.pose.covariance[0], 0.0, 1e-15);
  // Rotation about the camera's x is rotation about the base's -y: twist roll-pitch-yaw order.
  EXPECT_NEAR(m.twist.covariance[4 * 6 + 4], 4e-6 / 0.01, 1e-12);
  EXPECT_NEAR(m.twist.covariance[0], 1e-6 / 0.01, 1e-12);
}

TEST(OdometryMsg, VelocityIsUnknownOnFirstAndLostFrames) {
  for (acvo::Tracking t : {acvo::Tracking::kFirstFrame, acvo::Tracking::kLost}) {
    acvo::OdometryResult r =
        registered(Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity());
    r.tracking = t;
    const nav_msgs::Odometry m = toOdometryMsg(r, Eigen::Isometry3d::Identity(), {}, "cam");
    EXPECT_EQ(m.twist.twist.linear.x, 0.0);
    for (int d = 0; d < 6; ++d) EXPECT_EQ(m.twist.covariance[7 * d], kLostVariance);
  }
  // An interval of 0 (no previous stamp) too.
  acvo::OdometryResult r = registered(Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity());
  r.interval = 0.0;
  const nav_msgs::Odometry m = toOdometryMsg(r, Eigen::Isometry3d::Identity(), {}, "cam");
  EXPECT_EQ(m.twist.covariance[0], kLostVariance);
}

TEST(InfoMsg, CarriesTheResult) {
  acvo::OdometryResult r;
  r.tracking = acvo::Tracking::kLost;
  r.message = "too few points";
  r.solver.iterations = 17;
  r.solver.ell = 0.05;
  r.fixed_points = 1200;
  r.moving_points = 30;
  r.frame_index = 41;
  r.keyframe_index = 37;
  r.new_keyframe = true;
  r.fell_back_to_previous = true;
  r.interval = 0.066;
  r.second_start = true;
  InfoExtras extras;
  extras.ms_total = 12.5;
  extras.ms_latency = 40.25;
  extras.lost_count = 3;
  extras.guess_from_tf = true;
  const acvo::OdometryInfo info = toInfoMsg(r, {}, extras);
  EXPECT_TRUE(info.lost);
  EXPECT_EQ(info.tracking, acvo::toString(acvo::Tracking::kLost));
  EXPECT_EQ(info.iterations, 17);
  EXPECT_EQ(info.ell, 0.05);
  EXPECT_EQ(info.fixed_points, 1200u);
  EXPECT_EQ(info.moving_points, 30u);
  EXPECT_EQ(info.ms_total, 12.5);
  EXPECT_EQ(info.ms_latency, 40.25);
  EXPECT_TRUE(info.guess_from_tf);
  EXPECT_EQ(info.lost_count, 3u);
  EXPECT_EQ(info.message, "too few points");
  EXPECT_EQ(info.frame_index, 41u);
  EXPECT_EQ(info.keyframe_index, 37u);
  EXPECT_TRUE(info.new_keyframe);
  EXPECT_TRUE(info.fell_back_to_previous);
  EXPECT_EQ(info.interval, 0.066);
  EXPECT_TRUE(info.second_start);
  EXPECT_FALSE(info.second_start_kept);
}

// The dense depth term: its weight, or why it is off.
TEST(Diagnostics, DenseDepthTermSaysItsWeightOrWhyItIsOff) {
  EXPECT_EQ(denseWeightText(0.902, 0.0), "0.90");
  EXPECT_EQ(denseWeightText(1.0, 0.0), "1.00");
  EXPECT_EQ(denseWeightText(std::nan(""), 0.0), "not in use");
  EXPECT_EQ(denseWeightText(0.0, 0.012), "0 (off: the depth's stamp is not the colour's)");
  EXPECT_NE(denseWeightText(0.0, 0.0).find("shared between neighbouring pixels"),
            std::string::npos);
}

TEST(Diagnostics, NoDataFirstThenTheLastFramesJudgement) {
  using diagnostic_msgs::DiagnosticStatus;
  EXPECT_EQ(summarise(false, 0.0, 3.0, acvo::Tracking::kOk).message, "no data");
  EXPECT_EQ(summarise(true, 3.5, 3.0, acvo::Tracking::kOk).message, "no data");
  EXPECT_EQ(summarise(true, 3.5, 3.0, acvo::Tracking::kOk).level, DiagnosticStatus::ERROR);
  EXPECT_EQ(summarise(true, 0.1, 3.0, acvo::Tracking::kFirstFrame).level, DiagnosticStatus::OK);
  const DiagnosticSummary hard = summarise(true, 0.1, 3.0, acvo::Tracking::kHard);
  EXPECT_EQ(hard.level, DiagnosticStatus::WARN);
  EXPECT_EQ(hard.message, "hard to track");
  EXPECT_EQ(summarise(true, 0.1, 3.0, acvo::Tracking::kLost).message, "lost");
  EXPECT_EQ(summarise(true, 0.1, 3.0, acvo::Tracking::kBadFrame).message, "bad input");
  EXPECT_EQ(summarise(true, 0.1, 3.0, acvo::Tracking::kBadFrame).level, DiagnosticStatus::ERROR);
  // Paused says so, whatever came before (no frames come while paused).
  const DiagnosticSummary paused = summarise(true, 30.0, 3.0, acvo::Tracking::kOk, true);
  EXPECT_EQ(paused.level, DiagnosticStatus::WARN);
  EXPECT_EQ(paused.message, "paused");
}

TEST(NullOdometryMsg, IsRtabmapsLostMessage) {
  std_msgs::Header h;
  h.frame_id = "odom";
  const nav_msgs::Odometry m = nullOdometryMsg(h, "base_link");
  EXPECT_EQ(m.header.frame_id, "odom");
  EXPECT_EQ(m.child_frame_id, "base_link");
  EXPECT_EQ(m.pose.pose.orientation.w, 0.0);
  EXPECT_EQ(m.pose.pose.orientation.x, 0.0);
  EXPECT_EQ(m.pose.pose.position.x, 0.0);
  for (int d = 0; d < 6; ++d) {
    EXPECT_EQ(m.pose.covariance[7 * d], kLostVariance);
    EXPECT_EQ(m.twist.covariance[7 * d], kLostVariance);
  }
}

}  // namespace
}  // namespace acvo_ros
