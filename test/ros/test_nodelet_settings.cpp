// The nodelet's own settings (NodeletSettings) from a private namespace, without a ROS master:
// the defaults a robot needs, every key read with its type checked, values out of range and
// combinations that cannot work reported and replaced, the old names mapped.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "nodelet_settings.hpp"

namespace acvo_ros {
namespace {

using XmlRpc::XmlRpcValue;

std::string joined(const std::vector<std::string>& problems) {
  std::string all;
  for (const auto& p : problems) all += p + "\n";
  return all;
}

XmlRpcValue emptyNamespace() {
  XmlRpcValue ns;
  ns["unrelated"] = 1;  // a struct
  return ns;
}

TEST(NodeletSettings, DefaultsAreARobotsRep105Frames) {
  NodeletSettings s;
  EXPECT_TRUE(loadNodeletSettings(emptyNamespace(), s).empty());
  EXPECT_EQ(s.odom_frame_id, "odom");
  EXPECT_EQ(s.base_frame_id, "base_link");
  EXPECT_FALSE(s.base_is_optical_frame);
  EXPECT_TRUE(s.guess_frame_id.empty());
  EXPECT_TRUE(s.publish_tf);
  EXPECT_EQ(s.lost_odom, LostOdom::kHeld);
  EXPECT_TRUE(s.approx_sync);
  // A frame arriving while one is processed replaces the older one instead of queueing.
  EXPECT_LE(s.topic_queue_size, 2);
  EXPECT_GE(s.topic_queue_size, 1);
  EXPECT_EQ(s.sync_queue_size, 10);
  EXPECT_FALSE(s.initial_pose);
  EXPECT_DOUBLE_EQ(s.wait_for_transform_duration, 0.2);
  EXPECT_DOUBLE_EQ(s.max_time_gap, 1.0);
  EXPECT_DOUBLE_EQ(s.no_data_timeout, 3.0);
}

TEST(NodeletSettings, ReadsEveryKey) {
  XmlRpcValue ns;
  ns["odom_frame_id"] = std::string("/vo");
  ns["base_frame_id"] = std::string("/robot");
  ns["guess_frame_id"] = std::string("odom");
  ns["publish_tf"] = false;
  ns["wait_for_transform_duration"] = 1;  // an integer is fine for a double
  ns["max_time_gap"] = 2.5;
  ns["no_data_timeout"] = 7.0;
  ns["lost_odom"] = std::string("none");
  ns["approx_sync"] = false;
  ns["approx_sync_max_interval"] = 0.02;
  ns["topic_queue_size"] = 1;
  ns["sync_queue_size"] = 5;
  ns["camera"] = std::string("fr2");
  ns["initial_pose"] = std::string("1 -2 0.5 0 0 1.5707963267948966");
  NodeletSettings s;
  const auto problems = loadNodeletSettings(ns, s);
  EXPECT_TRUE(problems.empty()) << joined(problems);
  EXPECT_EQ(s.odom_frame_id, "vo");  // leading '/' stripped
  EXPECT_EQ(s.base_frame_id, "robot");
  EXPECT_EQ(s.guess_frame_id, "odom");
  EXPECT_FALSE(s.publish_tf);
  EXPECT_DOUBLE_EQ(s.wait_for_transform_duration, 1.0);
  EXPECT_DOUBLE_EQ(s.max_time_gap, 2.5);
  EXPECT_DOUBLE_EQ(s.no_data_timeout, 7.0);
  EXPECT_EQ(s.lost_odom, LostOdom::kNone);
  EXPECT_FALSE(s.approx_sync);
  EXPECT_DOUBLE_EQ(s.approx_sync_max_interval, 0.02);
  EXPECT_EQ(s.topic_queue_size, 1);
  EXPECT_EQ(s.sync_queue_size, 5);
  EXPECT_EQ(s.intrinsics.camera, "fr2");
  ASSERT_TRUE(s.initial_pose);
  EXPECT_NEAR(s.initial_pose->translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(s.initial_pose->translation().y(), -2.0, 1e-12);
  // Yaw 90 degrees: the base's x points along the odometry frame's y.
  const Eigen::Vector3d x = s.initial_pose->linear() * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x.y(), 1.0, 1e-12);
}

TEST(NodeletSettings, WrongTypesAndRangesAreReportedAndTheValueKept) {
  XmlRpcValue ns;
  ns["publish_tf"] = std::string("yes");
  ns["topic_queue_size"] = 0;
  ns["sync_queue_size"] = 2.5;
  ns["wait_for_transform_duration"] = -1.0;
  ns["lost_odom"] = std::string("hold");
  ns["fx"] = 500.0;  // without fy, cx, cy
  NodeletSettings s;
  const auto problems = loadNodeletSettings(ns, s);
  const std::string all = joined(problems);
  EXPECT_EQ(problems.size(), 6u) << all;
  for (const char* key : {"~publish_tf", "~topic_queue_size", "~sync_queue_size",
                          "~wait_for_transform_duration", "~lost_odom", "fx, fy, cx, cy"}) {
    EXPECT_NE(all.find(key), std::string::npos) << key << " not named in:\n" << all;
  }
  const NodeletSettings defaults;
  EXPECT_EQ(s.publish_tf, defaults.publish_tf);
  EXPECT_EQ(s.topic_queue_size, defaults.topic_queue_size);
  EXPECT_EQ(s.sync_queue_size, defaults.sync_queue_size);
  EXPECT_EQ(s.wait_for_transform_duration, defaults.wait_for_transform_duration);
  EXPECT_EQ(s.lost_odom, defaults.lost_odom);
  EXPECT_FALSE(s.intrinsics.explicitValues());
  EXPECT_EQ(s.intrinsics.fx, 0.0);
}

TEST(NodeletSettings, InitialPoseMustBeSixFiniteNumbers) {
  for (const std::string bad : {"1 2 3", "1 2 3 4 5 6 7", "1 2 3 a 5 6", "1 2 3 nan 0 0"}) {
    XmlRpcValue ns;
    ns["initial_pose"] = bad;
    NodeletSettings s;
    const auto problems = loadNodeletSettings(ns, s);
    ASSERT_EQ(problems.size(), 1u) << bad;
    EXPECT_NE(problems[0].find("~initial_pose"), std::string::npos) << problems[0];
    EXPECT_FALSE(s.initial_pose) << bad;
  }
  // A YAML list works too; an empty string is no initial pose.
  XmlRpcValue ns;
  ns["initial_pose"][0] = 0.5;
  for (int k = 1; k < 6; ++k) ns["initial_pose"][k] = 0;
  NodeletSettings s;
  EXPECT_TRUE(loadNodeletSettings(ns, s).empty());
  ASSERT_TRUE(s.initial_pose);
  EXPECT_EQ(s.initial_pose->translation().x(), 0.5);
  XmlRpcValue empty;
  empty["initial_pose"] = std::string("");
  NodeletSettings e;
  EXPECT_TRUE(loadNodeletSettings(empty, e).empty());
  EXPECT_FALSE(e.initial_pose);
}

TEST(NodeletSettings, RollPitchYawFollowRosConvention) {
  // R = Rz(yaw) Ry(pitch) Rx(roll), as tf2's setRPY: pitch 90 degrees turns x down to -z.
  const auto pose = parsePose6("0 0 0 0 1.5707963267948966 0", nullptr);
  ASSERT_TRUE(pose);
  const Eigen::Vector3d x = pose->linear() * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x.z(), -1.0, 1e-12);
  const auto roll = parsePose6("0 0 0 1.5707963267948966 0 0", nullptr);
  ASSERT_TRUE(roll);
  EXPECT_NEAR((roll->linear() * Eigen::Vector3d::UnitY()).z(), 1.0, 1e-12);
}

TEST(NodeletSettings, OldNamesAreTakenWithTheirMeaningAndSaidSo) {
  // queue_size (one size for everything) is now the synchroniser's.
  XmlRpcValue ns;
  ns["queue_size"] = 40;
  NodeletSettings s;
  auto problems = loadNodeletSettings(ns, s);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("sync_queue_size"), std::string::npos) << problems[0];
  EXPECT_EQ(s.sync_queue_size, 40);
  EXPECT_EQ(s.topic_queue_size, NodeletSettings().topic_queue_size);

  // publish_null_when_lost has rtabmap's meaning: true publishes a null message, false nothing.
  for (bool value : {true, false}) {
    XmlRpcValue old;
    old["publish_null_when_lost"] = value;
    NodeletSettings t;
    problems = loadNodeletSettings(old, t);
    ASSERT_EQ(problems.size(), 1u);
    EXPECT_NE(problems[0].find("lost_odom"), std::string::npos) << problems[0];
    EXPECT_EQ(t.lost_odom, value ? LostOdom::kNull : LostOdom::kNone);
  }
  // lost_odom wins when both are given.
  XmlRpcValue both;
  both["publish_null_when_lost"] = true;
  both["lost_odom"] = std::string("held");
  NodeletSettings u;
  problems = loadNodeletSettings(both, u);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(u.lost_odom, LostOdom::kHeld);
}

TEST(NodeletSettings, AGuessFrameThatCannotWorkIsRefused) {
  // The correction odom -> guess would be a loop, or a second parent of the base.
  const std::vector<std::pair<std::string, std::string>> cases = {{"guess_frame_id", "odom"},
                                                                  {"guess_frame_id", "base_link"}};
  for (const auto& [key, value] : cases) {
    XmlRpcValue ns;
    ns[key] = value;
    NodeletSettings s;
    const auto problems = loadNodeletSettings(ns, s);
    ASSERT_EQ(problems.size(), 1u) << value;
    EXPECT_NE(problems[0].find("~guess_frame_id"), std::string::npos) << problems[0];
    EXPECT_TRUE(s.guess_frame_id.empty());
  }
  // With base_is_optical_frame the base is not in TF: no guess can be looked up.
  XmlRpcValue ns;
  ns["guess_frame_id"] = std::string("wheel_odom");
  ns["base_frame_id"] = std::string("acvo_camera");
  ns["base_is_optical_frame"] = true;
  NodeletSettings s;
  EXPECT_EQ(loadNodeletSettings(ns, s).size(), 1u);
  EXPECT_TRUE(s.guess_frame_id.empty());
  // A guess frame of its own with odom renamed (rtabmap's vo -> odom -> base_link) is fine.
  XmlRpcValue good;
  good["guess_frame_id"] = std::string("odom");
  good["odom_frame_id"] = std::string("vo");
  NodeletSettings g;
  EXPECT_TRUE(loadNodeletSettings(good, g).empty());
  EXPECT_EQ(g.guess_frame_id, "odom");
}

TEST(NodeletSettings, DescribeNamesTheFrames) {
  NodeletSettings s;
  s.guess_frame_id = "odom";
  s.odom_frame_id = "vo";
  const std::string d = describe(s);
  EXPECT_NE(d.find("odom_frame_id=vo"), std::string::npos) << d;
  EXPECT_NE(d.find("base_frame_id=base_link"), std::string::npos) << d;
  EXPECT_NE(d.find("guess_frame_id=odom"), std::string::npos) << d;
}

}  // namespace
}  // namespace acvo_ros
