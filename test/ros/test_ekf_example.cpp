// config/ekf.yaml and config/ekf_2d.yaml (robot_localization's ekf_localization_node,
// launch/robot_ekf.launch) against what acvo publishes. robot_localization is not packaged in
// Debian, so the filter itself does not run here; this checks what the filter would be given:
// every field it fuses from /acvo/odom is one acvo fills, with a positive, finite covariance
// below the "unknown" 1e6 while tracking, and the lost frames' twist says "unknown"; the planar
// file is in two_d_mode and fuses the wheels' zero sideways and vertical speed; and the reason
// the pose is fused as differences only with lost_odom: none (a held pose would be read as a
// confident zero velocity) holds for what acvo publishes.
#include <array>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "acvo/odometry/odometry.hpp"
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

YAML::Node loadExample(const std::string& file) {
  return YAML::LoadFile(std::string(ACVO_SOURCE_DIR) + "/config/" + file);
}

Fused fromExample(const std::string& file, const std::string& sensor) {
  const YAML::Node yaml = loadExample(file);
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
  params.selection.target_points = 3000;  // 1500 at 320x240: quick
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
    // and stays finite and below 1e6.
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
  checkAgainstAcvo(fromExample("ekf.yaml", "odom1"), "config/ekf.yaml as shipped (twist)");
}

// Both files: the filter publishes odom -> base_link in acvo's frames (acvo runs with
// publish_tf false beside it, the base controller's own odom -> base_link is off).
TEST(EkfExample, TheFilterOwnsOdomToBaseInAcvosFrames) {
  for (const char* file : {"ekf.yaml", "ekf_2d.yaml"}) {
    SCOPED_TRACE(file);
    const YAML::Node yaml = loadExample(file);
    EXPECT_TRUE(yaml["publish_tf"].as<bool>(false));
    EXPECT_EQ(yaml["world_frame"].as<std::string>(""), yaml["odom_frame"].as<std::string>("-"));
    EXPECT_EQ(yaml["odom_frame"].as<std::string>(""), NodeletSettings().odom_frame_id);
    EXPECT_EQ(yaml["base_link_frame"].as<std::string>(""), NodeletSettings().base_frame_id);
  }
  EXPECT_FALSE(loadExample("ekf.yaml")["two_d_mode"].as<bool>(true)) << "the 6-DoF example";
}

// A planar robot: two_d_mode, and the wheels' vy and vz fused (zero: the base neither slides
// sideways nor moves up) with their forward speed and yaw rate; acvo's planar twist.
TEST(EkfExample, ThePlanarExampleIsTwoDAndFusesTheWheelsZeroSidewaysAndVerticalSpeed) {
  const YAML::Node yaml = loadExample("ekf_2d.yaml");
  EXPECT_TRUE(yaml["two_d_mode"].as<bool>(false)) << "config/ekf_2d.yaml is the planar example";
  const Fused wheels = fromExample("ekf_2d.yaml", "odom0");
  EXPECT_NE(wheels.topic, "/acvo/odom");
  EXPECT_FALSE(wheels.differential);
  EXPECT_TRUE(wheels.config[kTwist + 0]) << "the wheels' forward speed";
  EXPECT_TRUE(wheels.config[kTwist + 1]) << "the wheels' zero sideways speed";
  EXPECT_TRUE(wheels.config[kTwist + 2]) << "the wheels' zero vertical speed";
  EXPECT_TRUE(wheels.config[kTwist + 5]) << "the wheels' yaw rate";
  for (int d = 0; d < 6; ++d) EXPECT_FALSE(wheels.config[kPose + d]) << "wheel pose " << d;

  const Fused acvo = fromExample("ekf_2d.yaml", "odom1");
  EXPECT_TRUE(acvo.config[kTwist + 0] && acvo.config[kTwist + 1] && acvo.config[kTwist + 5])
      << "acvo's planar twist: vx, vy, vyaw";
  checkAgainstAcvo(acvo, "config/ekf_2d.yaml (planar twist)");
}

// robot_localization's differential mode (RosFilter::preparePose) turns two consecutive poses
// of a sensor into a velocity, (pose_k - pose_k-1) / dt, with the covariance
// (covariance_k + covariance_k-1) * dt. With lost_odom: held a lost frame repeats the held
// pose (no motion guess here): a zero velocity, one frame into the loss with a standard
// deviation well below the speed the robot goes on at: the filter would stop it. With
// lost_odom: none those messages are not sent. Hence config/ekf.yaml fuses the twist, and the
// pose only with lost_odom: none.
TEST(EkfExample, TheDifferentialPoseWouldReadAHeldPoseAsAConfidentStop) {
  Fused f = fromExample("ekf.yaml", "odom1");
  for (int d = 0; d < 6; ++d) {
    f.config[kPose + d] = true;
    f.config[kTwist + d] = false;
  }
  f.differential = true;
  checkAgainstAcvo(f, "differential pose");

  constexpr int kTracked = 5, kLost = 5;
  const std::vector<nav_msgs::Odometry> msgs = acvoMessages(kTracked, kLost);
  const auto position = [](const nav_msgs::Odometry& m) {
    return Eigen::Vector3d(m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z);
  };
  const auto stamp = [](const nav_msgs::Odometry& m) { return m.header.stamp.toSec(); };
  const nav_msgs::Odometry& before = msgs[kTracked - 2];
  const nav_msgs::Odometry& last_good = msgs[kTracked - 1];
  const double speed =
      (position(last_good) - position(before)).norm() / (stamp(last_good) - stamp(before));
  ASSERT_GT(speed, 0.05) << "the example robot moves";

  // lost_odom: held, the first lost frame as the filter differentiates it.
  const nav_msgs::Odometry& first_lost = msgs[kTracked];
  const double dt = stamp(first_lost) - stamp(last_good);
  const double velocity = (position(first_lost) - position(last_good)).norm() / dt;
  const double deviation =
      std::sqrt((first_lost.pose.covariance[0] + last_good.pose.covariance[0]) * dt);
  std::cout << "[ MEASURED ] differential pose, lost_odom held: speed " << speed
            << " m/s, first lost frame read as " << velocity << " m/s +- " << deviation << " m/s\n";
  EXPECT_EQ(velocity, 0.0) << "a lost frame holds the pose";
  EXPECT_LT(deviation, 0.5 * speed) << "the zero velocity is confident: the reason config/ekf.yaml"
                                       " offers the differential pose only with lost_odom: none";
  for (int k = kTracked; k < kTracked + kLost; ++k) {
    EXPECT_EQ(position(msgs[k]), position(last_good)) << "frame " << k << ": the held pose";
  }
}

TEST(EkfExample, WheelOdometryIsASecondSourceNotAcvo) {
  const Fused wheels = fromExample("ekf.yaml", "odom0");
  EXPECT_NE(wheels.topic, "/acvo/odom");
}

}  // namespace
}  // namespace acvo_ros
