// config/ekf.yaml (robot_localization's ekf_localization_node, launch/robot_ekf.launch) against
// what acvo publishes. robot_localization is not packaged in Debian, so the filter itself does
// not run here; this checks what the filter would be given: every field it fuses from
// /acvo/odom is one acvo fills, with a positive, finite covariance below the "unknown" 1e6
// while tracking, and, after tracking was lost for a while, a pose covariance that is still
// finite and below 1e6 (a filter keeps using it), while the lost frames' twist says "unknown".
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "acvo/odometry.hpp"
#include "covariance.hpp"
#include "messages.hpp"
#include "nodelet_settings.hpp"
#include "synthetic_room.hpp"

namespace acvo_ros {
namespace {

constexpr int kPose = 0, kTwist = 6, kAcceleration = 12;  // offsets in robot_localization's 15

struct Fused {
  std::string topic;
  std::array<bool, 15> config{};
  bool differential = false;
  std::string base_frame;
};

Fused fromExample(const std::string& sensor) {
  const YAML::Node yaml = YAML::LoadFile(std::string(ACVO_SOURCE_DIR) + "/config/ekf.yaml");
  Fused f;
  f.topic = yaml[sensor].as<std::string>();
  const YAML::Node config = yaml[sensor + "_config"];
  EXPECT_EQ(config.size(), 15u);
  for (std::size_t k = 0; k < 15 && k < config.size(); ++k) f.config[k] = config[k].as<bool>();
  f.differential = yaml[sensor + "_differential"].as<bool>(false);
  f.base_frame = yaml["base_link_frame"].as<std::string>();
  return f;
}

// The acvo odometry of an example robot: tracked frames of the synthetic room, then
// `lost_frames` frames without valid depth (0.1 s apart).
std::vector<nav_msgs::Odometry> acvoMessages(int tracked_frames, int lost_frames) {
  acvo::Params params;
  params.selection.target_points = 1500;  // 320x240: quick
  acvo::Odometry odometry(params);
  const acvo::Camera camera = acvo_test::testCamera();
  Eigen::Isometry3d base_from_camera = Eigen::Isometry3d::Identity();
  base_from_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // REP 103 optical frame
  base_from_camera.translation() << 0.1, 0.0, 0.3;
  std::vector<nav_msgs::Odometry> out;
  for (int k = 0; k < tracked_frames + lost_frames; ++k) {
    const acvo_test::RgbdImage image =
        acvo_test::renderRoom(acvo_test::worldFromFirstCamera() * acvo_test::cameraPose(k), camera);
    acvo::Frame frame;
    frame.color = image.rgb;
    frame.order = acvo::ColorOrder::kRgb;
    frame.depth = k < tracked_frames ? image.depth : cv::Mat::zeros(image.depth.size(), CV_32FC1);
    frame.camera = camera;
    frame.stamp = 100.0 + 0.1 * k;
    const acvo::OdometryResult r = odometry.process(frame);
    EXPECT_EQ(r.tracking == acvo::Tracking::kLost, k >= tracked_frames) << "frame " << k;
    std_msgs::Header header;
    header.frame_id = NodeletSettings().odom_frame_id;
    header.stamp.fromSec(frame.stamp);
    out.push_back(toOdometryMsg(r, base_from_camera, header, NodeletSettings().base_frame_id));
  }
  return out;
}

void expectUsable(const nav_msgs::Odometry::_pose_type::_covariance_type& covariance, int d,
                  const std::string& what) {
  const double v = covariance[7 * d];
  EXPECT_TRUE(std::isfinite(v)) << what << " " << d;
  EXPECT_GT(v, 0.0) << what << " " << d << ": robot_localization needs a positive variance";
  EXPECT_LT(v, kLostVariance) << what << " " << d;
}

void checkAgainstAcvo(const Fused& f, const std::string& variant) {
  SCOPED_TRACE(variant);
  EXPECT_EQ(f.topic, "/acvo/odom") << "the driver launch files publish acvo's odometry there";
  EXPECT_EQ(f.base_frame, NodeletSettings().base_frame_id) << "acvo's twist is in its base frame";
  bool pose = false, twist = false;
  for (int d = 0; d < 6; ++d) {
    pose = pose || f.config[kPose + d];
    twist = twist || f.config[kTwist + d];
  }
  for (int d = 0; d < 3; ++d) {
    EXPECT_FALSE(f.config[kAcceleration + d]) << "acvo gives no acceleration";
  }
  EXPECT_TRUE(pose || twist) << "nothing of acvo is fused";
  EXPECT_FALSE(pose && twist) << "pose and twist of one odometry are the same information";
  // acvo's pose drifts from its own origin: fused as differences only.
  if (pose) {
    EXPECT_TRUE(f.differential) << "acvo's pose must be fused with differential: true";
  }

  constexpr int kTracked = 5, kLost = 5;
  const std::vector<nav_msgs::Odometry> msgs = acvoMessages(kTracked, kLost);
  for (int k = 1; k < kTracked; ++k) {  // the first frame has no velocity yet
    for (int d = 0; d < 6; ++d) {
      if (f.config[kTwist + d]) expectUsable(msgs[k].twist.covariance, d, "tracked twist");
      if (f.config[kPose + d]) expectUsable(msgs[k].pose.covariance, d, "tracked pose");
    }
  }
  const nav_msgs::Odometry& last_good = msgs[kTracked - 1];
  const nav_msgs::Odometry& lost = msgs.back();
  for (int d = 0; d < 6; ++d) {
    // After 0.5 s lost the pose's covariance has grown by what the held pose may be wrong by,
    // and stays usable: the filter keeps fusing the pose (differential) after a loss.
    expectUsable(lost.pose.covariance, d, "pose after a loss");
    EXPECT_GT(lost.pose.covariance[7 * d], last_good.pose.covariance[7 * d]);
    // The lost frame's velocity is unknown: zero with 1e6, which the filter weighs as nothing.
    EXPECT_EQ(lost.twist.covariance[7 * d], kLostVariance);
  }
  EXPECT_EQ(lost.twist.twist.linear.x, 0.0);
  // lost_speed 1 m/s for 0.5 s: (0.5 m)^2 added to the position's variance, at least.
  EXPECT_GE(lost.pose.covariance[0] - last_good.pose.covariance[0], 0.25 * (1.0 - 1e-9));
  std::cout << "[ MEASURED ] " << variant << ": position variance " << last_good.pose.covariance[0]
            << " m^2 tracked, " << lost.pose.covariance[0] << " m^2 after 0.5 s lost; twist "
            << "variance vx " << msgs[kTracked - 1].twist.covariance[0] << "\n";
}

TEST(EkfExample, FusesWhatAcvoFillsAndKeepsUsingThePoseAfterALoss) {
  checkAgainstAcvo(fromExample("odom1"), "config/ekf.yaml as shipped (twist)");
}

TEST(EkfExample, TheDocumentedDifferentialPoseVariantWorksToo) {
  Fused f = fromExample("odom1");
  for (int d = 0; d < 6; ++d) {
    f.config[kPose + d] = true;
    f.config[kTwist + d] = false;
  }
  f.differential = true;
  checkAgainstAcvo(f, "differential pose");
}

TEST(EkfExample, WheelOdometryIsASecondSourceNotAcvo) {
  const Fused wheels = fromExample("odom0");
  EXPECT_NE(wheels.topic, "/acvo/odom");
}

}  // namespace
}  // namespace acvo_ros
