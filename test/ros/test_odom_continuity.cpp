// The published odom pose through losses and recoveries (odom_continuity.hpp), on results of
// the odometry written out by hand: what it does with each kind of frame, without images.
#include <gtest/gtest.h>

#include "acvo/math/se3.hpp"
#include "odom_continuity.hpp"

namespace acvo_ros {
namespace {

using acvo::Tracking;

Eigen::Isometry3d along(double x, double yaw = 0.0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << x, 0.0, 0.0;
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).matrix();
  return t;
}

acvo::OdometryResult result(Tracking tracking, const Eigen::Isometry3d& pose,
                            std::uint64_t index, std::uint64_t keyframe, bool new_keyframe = false) {
  acvo::OdometryResult r;
  r.tracking = tracking;
  r.pose = pose;
  r.frame_index = index;
  r.keyframe_index = keyframe;
  r.new_keyframe = new_keyframe;
  r.pose_covariance = acvo::originCovariance();
  return r;
}

bool near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return a.isApprox(b, 1e-9);
}

class Continuity : public ::testing::Test {
 protected:
  ContinuousOdom::Pose feed(const acvo::OdometryResult& r,
                            const std::optional<Eigen::Isometry3d>& guess = std::nullopt) {
    stamp_ += 0.1;
    return odom_.update(r, guess, stamp_, params_);
  }
  ContinuousOdom odom_;
  acvo::OdometryParams params_;
  double stamp_ = 100.0;
};

TEST_F(Continuity, TrackedFramesArePublishedAsTheOdometryGivesThem) {
  EXPECT_TRUE(near(feed(result(Tracking::kFirstFrame, along(0.5), 0, 0)).pose, along(0.5)));
  EXPECT_TRUE(near(feed(result(Tracking::kOk, along(0.6), 1, 0)).pose, along(0.6)));
  EXPECT_TRUE(near(feed(result(Tracking::kHard, along(0.7, 0.1), 2, 0)).pose, along(0.7, 0.1)));
}

// Without a guess: held while lost; the recovery registered to the old keyframe says the camera
// moved 0.3 m meanwhile: the published pose does not jump, and goes on from there.
TEST_F(Continuity, WithoutAGuessTheRecoveryDoesNotJumpAndTheBlackoutWidensTheCovariance) {
  feed(result(Tracking::kFirstFrame, along(0.0), 0, 0));
  feed(result(Tracking::kOk, along(0.1), 1, 0));
  acvo::OdometryResult lost = result(Tracking::kLost, along(0.1), 2, 0);
  lost.pose_covariance += acvo::lostGrowth(0.1, params_);
  const ContinuousOdom::Pose held = feed(lost);
  EXPECT_TRUE(near(held.pose, along(0.1)));
  EXPECT_TRUE(odom_.lost());
  const ContinuousOdom::Pose back = feed(result(Tracking::kOk, along(0.4), 3, 0));
  EXPECT_TRUE(near(back.pose, along(0.1))) << "jumped to\n" << back.pose.matrix();
  EXPECT_FALSE(odom_.lost());
  // The blackout's growth is kept: the odometry's covariance fell back with its registration.
  EXPECT_GE(back.covariance(3, 3), acvo::lostGrowth(0.2, params_)(3, 3) * (1 - 1e-9));
  const ContinuousOdom::Pose next = feed(result(Tracking::kOk, along(0.45, 0.05), 4, 0));
  EXPECT_TRUE(near(next.pose, along(0.1) * along(0.4).inverse() * along(0.45, 0.05)));
  EXPECT_GE(next.covariance(3, 3), back.covariance(3, 3) * (1 - 1e-9));
}

// With a guess (the wheels): while lost the published pose follows it from the last tracked
// frame; the recovery continues from the guess's pose.
TEST_F(Continuity, WithAGuessTheLostFramesDeadReckonAndTheRecoveryContinues) {
  feed(result(Tracking::kFirstFrame, along(0.0), 0, 0));
  feed(result(Tracking::kOk, along(0.1), 1, 0));
  // Guesses are from the last tracked frame (frame 1): 0.1 m, then 0.2 m.
  EXPECT_TRUE(near(feed(result(Tracking::kLost, along(0.1), 2, 0), along(0.1)).pose, along(0.2)));
  EXPECT_TRUE(near(feed(result(Tracking::kLost, along(0.1), 3, 0), along(0.2)).pose, along(0.3)));
  // Registered to the old keyframe, 0.31 m measured, 0.3 m guessed: continues from the guess.
  const ContinuousOdom::Pose back = feed(result(Tracking::kOk, along(0.41), 4, 0), along(0.3));
  EXPECT_TRUE(near(back.pose, along(0.4)));
  EXPECT_TRUE(near(feed(result(Tracking::kOk, along(0.51), 5, 0)).pose, along(0.5)));
}

// A lost frame that becomes the odometry's reference: frames registered to it follow on from
// its published (dead-reckoned) pose, with the motion the camera measures from it.
TEST_F(Continuity, FramesRegisteredToALostReferenceFollowItsPublishedPose) {
  feed(result(Tracking::kFirstFrame, along(0.0), 0, 0));
  feed(result(Tracking::kOk, along(0.1), 1, 0));
  feed(result(Tracking::kLost, along(0.1), 2, 0), along(0.1));
  // The second lost frame replaces the reference (odometry: held pose 0.1, published 0.3).
  EXPECT_TRUE(
      near(feed(result(Tracking::kLost, along(0.1), 3, 3, true), along(0.2)).pose, along(0.3)));
  // A lost frame after it that does not replace it leaves the frames registered to it alone.
  feed(result(Tracking::kLost, along(0.1), 4, 3), along(0.05));
  const ContinuousOdom::Pose back = feed(result(Tracking::kOk, along(0.15), 5, 3), along(0.9));
  EXPECT_TRUE(near(back.pose, along(0.35))) << "the measured 5 cm from frame 3, not the guess";
}

// A restart that keeps the pose (new parameters, a live clock stepping back) while the pose
// dead-reckons on the guess: the odometry restarts from its own pose, the held one (0.1 m); the
// published pose goes on from the dead-reckoned 0.3 m instead of snapping back to it.
TEST_F(Continuity, ARestartThatKeepsThePoseGoesOnFromTheLastPublishedOne) {
  feed(result(Tracking::kFirstFrame, along(0.0), 0, 0));
  feed(result(Tracking::kOk, along(0.1), 1, 0));
  feed(result(Tracking::kLost, along(0.1), 2, 0), along(0.1));
  EXPECT_TRUE(near(feed(result(Tracking::kLost, along(0.1), 3, 0), along(0.2)).pose, along(0.3)));
  const ContinuousOdom::Pose restarted = feed(result(Tracking::kFirstFrame, along(0.1), 4, 4, true));
  EXPECT_TRUE(near(restarted.pose, along(0.3))) << "snapped back to\n" << restarted.pose.matrix();
  EXPECT_FALSE(odom_.lost());
  EXPECT_TRUE(near(feed(result(Tracking::kOk, along(0.15), 5, 4)).pose, along(0.35)));
  // Lost again, then a second restart: from the pose published last, again.
  EXPECT_TRUE(near(feed(result(Tracking::kLost, along(0.15), 6, 4), along(0.1)).pose, along(0.45)));
  EXPECT_TRUE(near(feed(result(Tracking::kFirstFrame, along(0.15), 7, 7, true)).pose, along(0.45)));
}

TEST_F(Continuity, AResetPublishesTheOdometrysPosesAsTheyAre) {
  feed(result(Tracking::kFirstFrame, along(0.0), 0, 0));
  feed(result(Tracking::kLost, along(0.0), 1, 0), along(0.2));
  feed(result(Tracking::kOk, along(0.5), 2, 0), along(0.3));  // correction of -0.2 m
  odom_.reset();
  EXPECT_TRUE(near(feed(result(Tracking::kFirstFrame, along(2.0), 0, 0)).pose, along(2.0)));
}

}  // namespace
}  // namespace acvo_ros
