// Synthetic trajectories: start pose, smoothness, requested speeds, staying in the room.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "synth/layout.hpp"
#include "synth/trajectory.hpp"

namespace acvo::synth {
namespace {

// Every kind that moves (`still` has its own test).
const MotionKind kAllKinds[] = {MotionKind::kRandom, MotionKind::kXyz, MotionKind::kRpy,
                                MotionKind::kCircle, MotionKind::kSway};

double angleBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

struct Speeds {
  double linear = 0, angular = 0;  // means over the sequence, m/s and rad/s
};

Speeds meanSpeeds(const std::vector<Eigen::Isometry3d>& poses, double rate) {
  Speeds s;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    s.linear += (poses[i].translation() - poses[i - 1].translation()).norm();
    s.angular += angleBetween(poses[i - 1], poses[i]);
  }
  const double duration = (poses.size() - 1) / rate;
  s.linear /= duration, s.angular /= duration;
  return s;
}

MotionOptions options(MotionKind kind, int frames, double speed = 0.3, std::uint64_t seed = 1) {
  MotionOptions o;
  o.kind = kind;
  o.frames = frames;
  o.speed = speed;
  o.seed = seed;
  return o;
}

TEST(SynthTrajectory, StartsAtTheStartPose) {
  for (MotionKind kind : kAllKinds) {
    const auto poses = makeTrajectory(options(kind, 10));
    ASSERT_EQ(poses.size(), 10u);
    EXPECT_LT((poses[0].matrix() - defaultStartPose().matrix()).norm(), 1e-12) << toString(kind);
    EXPECT_GT((poses[9].matrix() - poses[0].matrix()).norm(), 1e-3) << toString(kind);
  }
  // A custom start, rolled: still the first pose.
  MotionOptions o = options(MotionKind::kCircle, 5);
  o.start = defaultStartPose() * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  EXPECT_LT((makeTrajectory(o)[0].matrix() - o.start.matrix()).norm(), 1e-12);
}

TEST(SynthTrajectory, StillStandsAtTheStartAndSwayStaysWithinCentimetres) {
  for (const Eigen::Isometry3d& pose : makeTrajectory(options(MotionKind::kStill, 600))) {
    EXPECT_EQ(pose.matrix(), defaultStartPose().matrix());
  }
  const Eigen::Isometry3d start = defaultStartPose();
  double widest = 0.0, widest_angle = 0.0;
  const auto sway = makeTrajectory(options(MotionKind::kSway, 600));
  for (const Eigen::Isometry3d& pose : sway) {
    const Eigen::Vector3d offset =
        start.linear().transpose() * (pose.translation() - start.translation());
    EXPECT_LE(std::abs(offset.x()), 0.03 + 1e-12);
    EXPECT_LE(std::abs(offset.y()), 0.02 + 1e-12);
    EXPECT_NEAR(offset.z(), 0.0, 1e-12);
    widest = std::max(widest, offset.norm());
    widest_angle = std::max(widest_angle, angleBetween(start, pose));
  }
  EXPECT_GT(widest, 0.03);  // both axes reach near their amplitude within 20 s
  EXPECT_NEAR(widest_angle, 1.5 * M_PI / 180.0, 0.01 * M_PI / 180.0);
  EXPECT_EQ(parseMotionKind("still"), MotionKind::kStill);
  EXPECT_EQ(parseMotionKind("sway"), MotionKind::kSway);
  EXPECT_EQ(toString(MotionKind::kSway), "sway");
}

TEST(SynthTrajectory, DefaultStartLooksIntoTheRoom) {
  const Eigen::Isometry3d start = defaultStartPose();
  EXPECT_TRUE(start.linear().isUnitary(1e-12));
  EXPECT_NEAR(start.linear().determinant(), 1.0, 1e-12);
  const Eigen::Vector3d forward = start.linear().col(2), down = start.linear().col(1);
  EXPECT_LT((forward - (kLookAtTarget - kStartEye).normalized()).norm(), 1e-12);
  EXPECT_LT(down.z(), -0.9);                           // image y points down in the world
  EXPECT_NEAR(start.linear().col(0).z(), 0.0, 1e-12);  // no roll
}

TEST(SynthTrajectory, MeanSpeedsAsRequested) {
  for (double speed : {0.1, 0.3, 0.8}) {
    for (std::uint64_t seed : {1, 2, 3}) {
      const auto poses = makeTrajectory(options(MotionKind::kRandom, 300, speed, seed));
      const Speeds s = meanSpeeds(poses, 30.0);
      EXPECT_NEAR(s.linear, speed, 0.03 * speed) << "seed " << seed;
      EXPECT_NEAR(s.angular, speed * kAngularPerLinear, 0.05 * speed * kAngularPerLinear)
          << "seed " << seed;
    }
  }
  // xyz and rpy: 240 frames at 0.3 m/s are three whole back-and-forth segments.
  const Speeds xyz = meanSpeeds(makeTrajectory(options(MotionKind::kXyz, 241)), 30.0);
  EXPECT_NEAR(xyz.linear, 0.3, 0.01);
  EXPECT_NEAR(xyz.angular, 0.0, 1e-9);
  const Speeds rpy = meanSpeeds(makeTrajectory(options(MotionKind::kRpy, 226)), 30.0);
  EXPECT_NEAR(rpy.linear, 0.0, 1e-9);
  EXPECT_NEAR(rpy.angular, 0.3 * kAngularPerLinear, 0.02 * 0.3 * kAngularPerLinear);
  const Speeds circle = meanSpeeds(makeTrajectory(options(MotionKind::kCircle, 300)), 30.0);
  EXPECT_NEAR(circle.linear, 0.3, 0.003);
  EXPECT_GT(circle.angular, 0.05);  // it turns to keep looking at the centre
}

TEST(SynthTrajectory, SmoothWithoutJumps) {
  for (MotionKind kind : kAllKinds) {
    for (double speed : {0.3, 1.0}) {
      const double rate = 30.0;
      const auto poses = makeTrajectory(options(kind, 600, speed));
      double worst_acceleration = 0.0, worst_angular_acceleration = 0.0;
      for (std::size_t i = 1; i + 1 < poses.size(); ++i) {
        const Eigen::Vector3d a = (poses[i + 1].translation() - 2.0 * poses[i].translation() +
                                   poses[i - 1].translation()) *
                                  rate * rate;
        worst_acceleration = std::max(worst_acceleration, a.norm());
        // Change of the per-frame rotation between consecutive frames.
        const Eigen::Matrix3d step0 = poses[i - 1].linear().transpose() * poses[i].linear();
        const Eigen::Matrix3d step1 = poses[i].linear().transpose() * poses[i + 1].linear();
        const double change = Eigen::AngleAxisd(step0.transpose() * step1).angle() * rate * rate;
        worst_angular_acceleration = std::max(worst_angular_acceleration, change);
      }
      // Handheld-like bounds, scaling with the square of the speed (time runs faster).
      const double scale = std::max(1.0, std::pow(speed / 0.3, 2));
      // A jump in velocity of `speed` alone would show as speed * rate = 9 m/s^2 at 0.3 m/s.
      EXPECT_LT(worst_acceleration, 4.0 * scale) << toString(kind) << " speed " << speed;
      EXPECT_LT(worst_angular_acceleration, 6.0 * scale) << toString(kind) << " speed " << speed;
    }
  }
}

TEST(SynthTrajectory, StaysInTheRoomFacingTheFurniture) {
  const Eigen::Vector3d start_forward = defaultStartPose().linear().col(2);
  for (MotionKind kind : kAllKinds) {
    for (double speed : {0.1, 0.3, 1.5}) {
      for (std::uint64_t seed : {1, 4, 9}) {
        for (const Eigen::Isometry3d& pose : makeTrajectory(options(kind, 1800, speed, seed))) {
          const Eigen::Vector3d p = pose.translation();
          ASSERT_TRUE((p.array() > kRoomMin.array() + 0.3).all()) << toString(kind);
          ASSERT_TRUE((p.array() < kRoomMax.array() - 0.3).all()) << toString(kind);
          ASSERT_LT(p.y(), kFurnitureMinY - 0.2) << toString(kind) << " seed " << seed;
          const double turned =
              std::acos(std::clamp(pose.linear().col(2).dot(start_forward), -1.0, 1.0));
          ASSERT_LT(turned, 45.0 * M_PI / 180.0) << toString(kind) << " seed " << seed;
          // Every ray of a 640x480, f = 525 view reaches the single plane ahead.
          for (double x : {-320.0 / 525.0, 320.0 / 525.0})
            for (double y : {-240.0 / 525.0, 240.0 / 525.0})
              ASSERT_GT((pose.linear() * Eigen::Vector3d(x, y, 1.0)).y(), 0.1);
        }
      }
    }
  }
}

TEST(SynthTrajectory, DeterministicForASeed) {
  const auto a = makeTrajectory(options(MotionKind::kRandom, 50, 0.3, 7));
  const auto b = makeTrajectory(options(MotionKind::kRandom, 50, 0.3, 7));
  const auto c = makeTrajectory(options(MotionKind::kRandom, 50, 0.3, 8));
  double same = 0.0, different = 0.0;
  for (int i = 0; i < 50; ++i) {
    same += (a[i].matrix() - b[i].matrix()).norm();
    different += (a[i].matrix() - c[i].matrix()).norm();
  }
  EXPECT_EQ(same, 0.0);
  EXPECT_GT(different, 0.1);
}

TEST(SynthTrajectory, ZeroSpeedStandsStill) {
  for (MotionKind kind : kAllKinds) {
    const auto poses = makeTrajectory(options(kind, 20, 0.0));
    for (const auto& pose : poses)
      EXPECT_LT((pose.matrix() - defaultStartPose().matrix()).norm(), 1e-12) << toString(kind);
  }
}

TEST(SynthTrajectory, NamesAndBadOptions) {
  for (MotionKind kind : kAllKinds) EXPECT_EQ(parseMotionKind(toString(kind)), kind);
  EXPECT_FALSE(parseMotionKind("spiral"));
  EXPECT_THROW(Motion(options(MotionKind::kRandom, -1)), std::invalid_argument);
  EXPECT_THROW(Motion(options(MotionKind::kRandom, 10, -0.1)), std::invalid_argument);
  MotionOptions o = options(MotionKind::kXyz, 10);
  o.rate = 0.0;
  EXPECT_THROW(Motion{o}, std::invalid_argument);
}

}  // namespace
}  // namespace acvo::synth
