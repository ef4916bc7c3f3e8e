// The frame-to-frame pipeline: state, tracking judgement, covariance, bad frames.
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "acvo/odometry.hpp"
#include "acvo/se3.hpp"
#include "synth/sequence.hpp"

namespace acvo {
namespace {

synth::SynthSequence exactSequence(int frames) {
  synth::SequenceOptions o;
  o.frames = frames;
  o.noise = false;
  return synth::SynthSequence(o);
}

double translationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.inverse() * b).translation().norm();
}
double rotationErrorDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return logSE3(a.inverse() * b).head<3>().norm() * 180.0 / M_PI;
}

// Starts `odo` at the sequence's first pose and tracks its first `frames` frames.
void trackFirst(Odometry& odo, const synth::SynthSequence& seq, int frames) {
  odo.reset(seq.poses()[0]);
  for (int i = 0; i < frames; ++i) odo.process(seq.frame(i).toFrame());
}

Frame blankFrame(const Frame& like) {
  Frame f = like;
  f.depth = cv::Mat::zeros(like.depth.size(), CV_32FC1);
  f.stamp += 1.0 / 30.0;
  return f;
}

TEST(Odometry, FirstFrameThenTracksAnExactSequence) {
  const auto seq = exactSequence(6);
  Odometry odo;
  odo.reset(seq.poses()[0]);
  const OdometryResult first = odo.process(seq.frame(0).toFrame());
  EXPECT_EQ(first.tracking, Tracking::kFirstFrame);
  EXPECT_TRUE(first.pose.isApprox(seq.poses()[0]));
  ASSERT_NE(odo.keyframeCloud(), nullptr);
  EXPECT_GT(odo.keyframeCloud()->size(), 2000u);
  EXPECT_EQ(first.cloud.get(), odo.keyframeCloud());
  for (int i = 1; i < seq.size(); ++i) {
    const OdometryResult r = odo.process(seq.frame(i).toFrame());
    EXPECT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard)
        << toString(r.tracking) << ": " << r.message;
    const Eigen::Isometry3d true_motion = seq.poses()[i - 1].inverse() * seq.poses()[i];
    EXPECT_LT(translationError(true_motion, r.motion), 1.5e-3) << "frame " << i;
    EXPECT_LT(rotationErrorDeg(true_motion, r.motion), 0.1) << "frame " << i;
    EXPECT_LT(translationError(seq.poses()[i], r.pose), 1.5e-3 * i);
    // Covariance: symmetric positive definite, small for a well-constrained exact frame.
    const auto& C = r.motion_covariance;
    EXPECT_TRUE(C.allFinite());
    EXPECT_LT((C - C.transpose()).norm(), 1e-9 * C.norm());
    using Solver6 = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>;
    EXPECT_GT(Solver6(C).eigenvalues().minCoeff(), 0.0);
    EXPECT_LT(C.diagonal().maxCoeff(), 1e-2);
    EXPECT_GT(r.ms_cloud, 0.0);
    EXPECT_GT(r.solver.nnz, 0u);
  }
}

TEST(Odometry, BadFramesAreRejectedWithoutChangingTheState) {
  const auto seq = exactSequence(2);
  Odometry odo;
  const Frame good = seq.frame(0).toFrame();
  odo.process(good);
  const Eigen::Isometry3d pose = odo.pose();

  Frame empty;
  OdometryResult r = odo.process(empty);
  EXPECT_EQ(r.tracking, Tracking::kBadFrame);
  EXPECT_NE(r.message.find("empty"), std::string::npos) << r.message;

  Frame mismatch = good;
  mismatch.depth = cv::Mat::zeros(good.depth.rows / 2, good.depth.cols / 2, CV_32FC1);
  r = odo.process(mismatch);
  EXPECT_EQ(r.tracking, Tracking::kBadFrame);
  EXPECT_NE(r.message.find("depth"), std::string::npos) << r.message;

  Frame no_focal = good;
  no_focal.camera.fx = 0.0;
  EXPECT_EQ(odo.process(no_focal).tracking, Tracking::kBadFrame);

  EXPECT_TRUE(odo.pose().isApprox(pose));
  // The reference survived: the next good frame tracks.
  r = odo.process(seq.frame(1).toFrame());
  EXPECT_EQ(r.tracking, Tracking::kOk) << r.message;
}

TEST(Odometry, BlankFramesAreLostKeepThePoseAndTheReference) {
  const auto seq = exactSequence(4);
  Odometry odo;
  trackFirst(odo, seq, 2);
  const Eigen::Isometry3d pose1 = odo.pose();

  const OdometryResult lost = odo.process(blankFrame(seq.frame(1).toFrame()));
  EXPECT_EQ(lost.tracking, Tracking::kLost);
  EXPECT_NE(lost.message.find("too_few_points"), std::string::npos) << lost.message;
  EXPECT_NE(lost.message.find("no valid depth"), std::string::npos) << lost.message;
  EXPECT_TRUE(lost.pose.isApprox(pose1));
  EXPECT_GE(lost.motion_covariance.diagonal().minCoeff(), 1e5) << "lost: no confidence";
  EXPECT_TRUE(lost.motion.isApprox(Eigen::Isometry3d::Identity()));

  // Frame 3 registers against frame 1 (the reference the blank frame could not replace).
  const OdometryResult back = odo.process(seq.frame(3).toFrame());
  EXPECT_NE(back.tracking, Tracking::kLost) << back.message;
  EXPECT_LT(translationError(seq.poses()[3], back.pose), 3e-3);
}

TEST(Odometry, FlatColourFrameIsLostNamedAndKeepsTheReference) {
  const auto seq = exactSequence(4);
  Odometry odo;
  trackFirst(odo, seq, 2);
  const Eigen::Isometry3d pose1 = odo.pose();

  Frame flat = seq.frame(2).toFrame();  // valid depth, one colour: no gradient to select
  flat.color.setTo(cv::Scalar::all(128));
  const OdometryResult lost = odo.process(flat);
  EXPECT_EQ(lost.tracking, Tracking::kLost);
  EXPECT_NE(lost.message.find("no intensity gradient"), std::string::npos) << lost.message;
  EXPECT_TRUE(lost.pose.isApprox(pose1));

  const OdometryResult back = odo.process(seq.frame(3).toFrame());
  EXPECT_NE(back.tracking, Tracking::kLost) << back.message;
  EXPECT_LT(translationError(seq.poses()[3], back.pose), 3e-3);
}

// The constant-velocity prior is the last registered motion, per frame, whatever the stamps:
// across a pause of seconds it is one frame's motion (about 1 cm here), within the reach of
// the registration, not that motion times the frames the pause spans (3 s = 90 frames would
// be about 0.9 m, beyond it: the frame would be lost).
TEST(Odometry, MotionPriorAcrossAStampGapIsOneFramesMotion) {
  const auto seq = exactSequence(5);
  Odometry odo;
  trackFirst(odo, seq, 3);
  // The stream pauses for 3 s while the camera stands still at frame 2's pose.
  Frame paused = seq.frame(2).toFrame();
  paused.stamp += 3.0;
  OdometryResult r = odo.process(paused);
  EXPECT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard)
      << toString(r.tracking) << ": " << r.message;
  EXPECT_LT(r.motion.translation().norm(), 1.5e-3);
  EXPECT_LT(rotationErrorDeg(Eigen::Isometry3d::Identity(), r.motion), 0.1);
  // Then it moves on: one frame's motion again.
  for (int i = 3; i < 5; ++i) {
    Frame f = seq.frame(i).toFrame();
    f.stamp += 3.0;
    r = odo.process(f);
    EXPECT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard)
        << toString(r.tracking) << ": " << r.message;
  }
  EXPECT_LT(translationError(seq.poses()[4], r.pose), 1.5e-3 * 5);
}

// A single frame of noise (random colour, random depth) inside a sequence: lost, the pose
// stays finite, and the reference survives it: the next frame is registered against the last
// good one, so no motion is missed. (Re-seeding from the noise frame cost two frames of
// motion: 2.0 cm off at frame 5, where 1 mm is measured now.)
TEST(Odometry, ASingleFrameOfNoiseIsLostAndTheNextFrameTracksAgainstTheLastGoodOne) {
  const auto seq = exactSequence(6);
  Odometry odo;
  trackFirst(odo, seq, 3);
  const Eigen::Isometry3d pose2 = odo.pose();
  Frame noise = seq.frame(3).toFrame();
  cv::RNG rng(7);
  rng.fill(noise.color, cv::RNG::UNIFORM, 0, 256);
  rng.fill(noise.depth, cv::RNG::UNIFORM, 0.5, 4.0);
  const OdometryResult lost = odo.process(noise);
  EXPECT_EQ(lost.tracking, Tracking::kLost) << lost.message;
  EXPECT_NE(lost.message.find("do not overlap"), std::string::npos) << lost.message;
  EXPECT_TRUE(lost.pose.isApprox(pose2));
  for (int i = 4; i < 6; ++i) {
    const OdometryResult r = odo.process(seq.frame(i).toFrame());
    EXPECT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard)
        << "frame " << i << ": " << toString(r.tracking) << ": " << r.message;
    std::printf("  frame %d after the noise frame: %.4f m, %.3f deg off\n", i,
                translationError(seq.poses()[i], r.pose), rotationErrorDeg(seq.poses()[i], r.pose));
    EXPECT_LT(translationError(seq.poses()[i], r.pose), 1.5e-3 * i);
    EXPECT_LT(rotationErrorDeg(seq.poses()[i], r.pose), 0.1 * i);
  }
}

// Two lost frames in a row: the second becomes the reference (the view may have changed for
// good), so tracking goes on from there.
TEST(Odometry, TheSecondLostFrameInARowBecomesTheReference) {
  const auto seq = exactSequence(5);
  Odometry odo;
  trackFirst(odo, seq, 1);
  cv::RNG rng(3);
  for (int n = 0; n < 2; ++n) {
    Frame noise = seq.frame(1).toFrame();
    rng.fill(noise.color, cv::RNG::UNIFORM, 0, 256);
    rng.fill(noise.depth, cv::RNG::UNIFORM, 0.5, 4.0);
    EXPECT_EQ(odo.process(noise).tracking, Tracking::kLost);
  }
  // Frame 3 against the second noise frame: lost (the reference is noise now), then frame 4
  // against frame 3 tracks.
  EXPECT_EQ(odo.process(seq.frame(3).toFrame()).tracking, Tracking::kLost);
  const OdometryResult r = odo.process(seq.frame(4).toFrame());
  EXPECT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard)
      << toString(r.tracking) << ": " << r.message;
  const Eigen::Isometry3d true_motion = seq.poses()[3].inverse() * seq.poses()[4];
  EXPECT_LT(translationError(true_motion, r.motion), 1.5e-3);
}

TEST(Odometry, NaNAndOutOfRangeDepthNeverReachThePose) {
  const auto seq = exactSequence(2);
  Odometry odo;
  odo.process(seq.frame(0).toFrame());
  Frame f = seq.frame(1).toFrame();
  f.depth.setTo(std::numeric_limits<float>::quiet_NaN());
  OdometryResult r = odo.process(f);
  EXPECT_EQ(r.tracking, Tracking::kLost);
  EXPECT_TRUE(r.pose.matrix().allFinite());
  f.depth.setTo(100.0f);  // beyond max_depth everywhere
  r = odo.process(f);
  EXPECT_EQ(r.tracking, Tracking::kLost);
  EXPECT_TRUE(r.pose.matrix().allFinite());
}

TEST(Odometry, ResetStartsAgainFromTheGivenPose) {
  const auto seq = exactSequence(3);
  Odometry odo;
  odo.process(seq.frame(0).toFrame());
  odo.process(seq.frame(1).toFrame());
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  start.translation() << 1, 2, 3;
  odo.reset(start);
  EXPECT_EQ(odo.keyframeCloud(), nullptr);
  const OdometryResult r = odo.process(seq.frame(2).toFrame());
  EXPECT_EQ(r.tracking, Tracking::kFirstFrame);
  EXPECT_TRUE(r.pose.isApprox(start));
}

TEST(Odometry, DeterministicForTheSameFramesWhateverTheThreadCount) {
  const auto seq = exactSequence(4);
  Eigen::Isometry3d last[2];
  int iterations[2] = {0, 0};
  for (int run = 0; run < 2; ++run) {
    Params params;
    params.odometry.threads = run + 1;  // reductions run over fixed chunks in a fixed order
    Odometry odo(params);
    for (int i = 0; i < seq.size(); ++i) {
      const OdometryResult r = odo.process(seq.frame(i).toFrame());
      iterations[run] += r.solver.iterations;
      last[run] = r.pose;
    }
  }
  EXPECT_EQ(iterations[0], iterations[1]);
  EXPECT_EQ(last[0].matrix(), last[1].matrix());
}

}  // namespace
}  // namespace acvo
