// The frame-to-frame pipeline: state, tracking judgement, covariance, bad frames.
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
  ASSERT_NE(odo.lastCloud(), nullptr);
  EXPECT_GT(odo.lastCloud()->size(), 2000u);
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
  odo.reset(seq.poses()[0]);
  odo.process(seq.frame(0).toFrame());
  odo.process(seq.frame(1).toFrame());
  const Eigen::Isometry3d pose1 = odo.pose();

  const OdometryResult lost = odo.process(blankFrame(seq.frame(1).toFrame()));
  EXPECT_EQ(lost.tracking, Tracking::kLost);
  EXPECT_NE(lost.message.find("too_few_points"), std::string::npos) << lost.message;
  EXPECT_TRUE(lost.pose.isApprox(pose1));
  EXPECT_GE(lost.motion_covariance.diagonal().minCoeff(), 1e5) << "lost: no confidence";
  EXPECT_TRUE(lost.motion.isApprox(Eigen::Isometry3d::Identity()));

  // Frame 3 registers against frame 1 (the reference the blank frame could not replace).
  const OdometryResult back = odo.process(seq.frame(3).toFrame());
  EXPECT_NE(back.tracking, Tracking::kLost) << back.message;
  EXPECT_LT(translationError(seq.poses()[3], back.pose), 3e-3);
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
  EXPECT_EQ(odo.lastCloud(), nullptr);
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
