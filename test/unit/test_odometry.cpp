// The frame-to-frame pipeline: state, tracking judgement, covariance, bad frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <opencv2/core.hpp>

#include "acvo/cloud/depth.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/math/se3.hpp"
#include "synth/sequence.hpp"

namespace acvo {
namespace {

synth::SynthSequence exactSequence(int frames) {
  synth::SequenceOptions o;
  o.frames = frames;
  o.noise = false;
  return synth::SynthSequence(o);
}

// Six exact 320x240 frames at 0.5 m/s whose colour is taken 12 ms after their depth.
synth::SynthSequence lateColourSequence() {
  synth::SequenceOptions o;
  o.frames = 6;
  o.noise = false;
  o.speed = 0.5;
  o.colour_delay = 0.012;
  o.camera = synth::scaledDefaultCamera(320, 240);
  return synth::SynthSequence(o);
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  return v[v.size() / 2];
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

// The frame mirrored as cv::flip does, about its horizontal axis (flip_code 0), its vertical one
// (1) or both (-1), with the camera that says so: the mirrored axes' focal lengths negated, their
// centres mirrored. Each pixel back-projects to the point it did before.
Frame mirroredFrame(const Frame& f, int flip_code) {
  Frame out = f;
  cv::flip(f.color, out.color, flip_code);
  cv::flip(f.depth, out.depth, flip_code);
  if (flip_code <= 0) {
    out.camera.fy = -f.camera.fy;
    out.camera.cy = (f.camera.height - 1) - f.camera.cy;
  }
  if (flip_code != 0) {
    out.camera.fx = -f.camera.fx;
    out.camera.cx = (f.camera.width - 1) - f.camera.cx;
  }
  return out;
}

// A camera whose image axis is mirrored, as in ICL-NUIM's published intrinsics (fy -480, its
// renderer's y axis pointing up), is tracked as the same frames unmirrored are, on this rendered
// room. The largest errors over the 7 frames: 0.18 mm and 0.0042 deg as rendered, 0.17 mm and
// 0.0042 deg upside down, 0.15 mm and 0.0034 deg left to right, 0.22 mm and 0.0055 deg both.
TEST(Odometry, AMirroredImageAxisIsANegativeFocalLength) {
  synth::SequenceOptions o;
  o.frames = 8;
  o.speed = 0.5;
  const synth::SynthSequence seq(o);
  for (int flip_code : {-2, 0, 1, -1}) {  // -2: as rendered
    Odometry odo;
    odo.reset(seq.poses()[0]);
    double worst_mm = 0.0, worst_deg = 0.0;
    for (int i = 0; i < seq.size(); ++i) {
      const Frame frame = seq.frame(i).toFrame();
      const Frame input = flip_code < -1 ? frame : mirroredFrame(frame, flip_code);
      const OdometryResult r = odo.process(input);
      if (i == 0) {
        EXPECT_EQ(r.tracking, Tracking::kFirstFrame) << r.message;
        continue;
      }
      EXPECT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard)
          << "flip " << flip_code << ", frame " << i << ": " << r.message;
      const Eigen::Isometry3d true_motion = seq.poses()[i - 1].inverse() * seq.poses()[i];
      worst_mm = std::max(worst_mm, 1e3 * translationError(true_motion, r.motion));
      worst_deg = std::max(worst_deg, rotationErrorDeg(true_motion, r.motion));
    }
    std::printf("flip %d: at most %.2f mm and %.4f deg off the truth\n", flip_code, worst_mm,
                worst_deg);
    EXPECT_LT(worst_mm, 0.35) << "flip " << flip_code;
    EXPECT_LT(worst_deg, 0.01) << "flip " << flip_code;
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

  for (double stamp : {std::nan(""), double(INFINITY)}) {
    Frame bad_stamp = seq.frame(1).toFrame();
    bad_stamp.stamp = stamp;
    r = odo.process(bad_stamp);
    EXPECT_EQ(r.tracking, Tracking::kBadFrame);
    EXPECT_NE(r.message.find("stamp"), std::string::npos) << r.message;
  }

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

// Colour 12 ms after the depth at 0.5 m/s, depth exact: each cloud's points are where the
// surfaces were at the colour's instant. The second frame has no last motion to move its depth
// by, the later ones have one; both are moved by their own motion between the registration's
// stages (OdometryResult::depth_retimed), and their points land within a fraction of what the
// depth as it came puts them off by.
TEST(Odometry, DepthOfAnotherInstantIsMovedByTheFramesOwnMotion) {
  const synth::SynthSequence seq = lateColourSequence();
  for (const bool sync : {true, false}) {
    Params params;
    params.odometry.sync_depth = sync ? SyncDepth::kOwnMotion : SyncDepth::kNone;
    Odometry odo(params);
    odo.reset(seq.colourPose(0));
    for (int i = 0; i < seq.size(); ++i) {
      const Frame frame = seq.frame(i).toFrame();
      ASSERT_NE(frame.depth_stamp, frame.stamp);
      const OdometryResult r = odo.process(frame);
      ASSERT_TRUE(r.tracking == Tracking::kOk || r.tracking == Tracking::kHard ||
                  (i == 0 && r.tracking == Tracking::kFirstFrame))
          << toString(r.tracking) << ": " << r.message;
      EXPECT_NEAR(r.depth_delay, 0.012, 1e-9);
      EXPECT_EQ(r.depth_synced, sync && i >= 2) << "frame " << i;
      EXPECT_EQ(r.depth_retimed, sync && i >= 1) << "frame " << i;
      if (i == 0) continue;
      // The exact depth at the colour's instant, against the cloud's and the depth as it came:
      // the medians of the differences (a pixel on a depth edge is off by the edge's step).
      const cv::Mat truth = depthSeenFrom(frame.depth, frame.camera,
                                          seq.poses()[std::size_t(i)].inverse() * seq.colourPose(i));
      std::vector<double> cloud_error, as_it_came;
      for (std::size_t k = 0; k < r.cloud->size(); ++k) {
        const cv::Point p = r.cloud->pixels[k];
        const float z = truth.at<float>(p), z0 = frame.depth.at<float>(p);
        if (!(z > 0.f && z0 > 0.f)) continue;
        cloud_error.push_back(std::abs(r.cloud->points[k].z() - z));
        as_it_came.push_back(std::abs(z0 - z));
      }
      ASSERT_GT(cloud_error.size(), 500u);
      const double e = median(cloud_error), e0 = median(as_it_came);
      std::printf("  sync %d frame %d: median depth error %.4f mm, as it came %.4f mm\n", int(sync),
                  i, 1e3 * e, 1e3 * e0);
      // Measured: 0.15, 0.22, 0.06, 0.09, 0.08 of the error as it came (the rest: the coarse
      // levels' motion, and the forward projection's nearest pixel on slanted surfaces).
      if (sync) {
        EXPECT_LT(e, 0.3 * e0) << "frame " << i;
      } else {
        EXPECT_EQ(e, e0) << "frame " << i;
      }
    }
  }
  // Colour and depth of one instant: nothing is moved.
  Odometry odo;
  const auto same = exactSequence(3);
  for (int i = 0; i < same.size(); ++i) {
    const OdometryResult r = odo.process(same.frame(i).toFrame());
    EXPECT_FALSE(r.depth_synced || r.depth_retimed);
  }
}

// A single frame of noise (random colour, random depth) inside a sequence: lost, the pose
// stays finite, and the reference survives it: the next frame is registered against the last
// good one, so no motion is missed. (Re-seeding from the noise frame would cost two frames of
// motion: 2.0 cm off at frame 5, against under 0.1 mm measured.)
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

// Colour from a second camera (0.897 times the depth's focal length, exact depth): the colour
// check decides at the third frame (the evidence is clear: the early verdict); that frame
// becomes the keyframe, its cloud built again from the resampled colour (a grey value at a
// selected pixel tells which), and every frame after it is resampled by the ratio found. The
// frames given are not changed. reset() keeps the verdict, which concerns the camera;
// newCamera() drops it, takeColourCheck() carries it to another Odometry (a parameter change).
// With unregistered_colour as_given, the verdict alone. A registered camera: the verdict,
// nothing resampled.
TEST(Odometry, ColourFromASecondCameraIsResampledFromTheVerdictOn) {
  synth::SequenceOptions o;
  o.frames = 16;
  o.noise = false;
  o.colour_focal_ratio = 0.897;
  const synth::SynthSequence seq(o);
  Odometry odo;
  odo.reset(seq.poses()[0]);
  int verdict_at = -1;
  for (int i = 0; i < seq.size(); ++i) {
    const Frame frame = seq.frame(i).toFrame();
    const cv::Mat given = frame.color.clone();
    const OdometryResult r = odo.process(frame);
    EXPECT_EQ(cv::countNonZero(frame.color.reshape(1) != given.reshape(1)), 0) << i;
    EXPECT_NE(r.tracking, Tracking::kLost) << i;
    if (r.colour_verdict_now) {
      verdict_at = i;
      EXPECT_TRUE(r.new_keyframe);
      EXPECT_FALSE(r.colour_resampled);  // registered as it came, then rebuilt
      // The keyframe's colour is the resampled frame's.
      const Frame resampled = withColourResampled(frame, *odo.colourResampling());
      const LabelledCloud& key = *odo.keyframeCloud();
      ASSERT_FALSE(key.pixels.empty());
      const cv::Point p = key.pixels[key.pixels.size() / 2];
      EXPECT_EQ(key.gray.at<std::uint8_t>(p), grayImage(resampled).at<std::uint8_t>(p));
    }
    EXPECT_EQ(r.colour_resampled, verdict_at >= 0 && i > verdict_at) << i;
  }
  EXPECT_EQ(verdict_at, 2);
  ASSERT_EQ(odo.colourCheck().verdict().state, ColourDepthCheck::State::kUnregistered);
  ASSERT_TRUE(odo.colourResampling());
  EXPECT_NEAR(*odo.colourResampling(), 0.897, 0.025);
  EXPECT_NE(odo.describeColour().find("resampled"), std::string::npos) << odo.describeColour();

  odo.reset(seq.poses()[0]);
  EXPECT_TRUE(odo.colourResampling());
  Odometry next;
  next.takeColourCheck(odo.colourCheck());
  EXPECT_EQ(next.colourResampling(), odo.colourResampling());
  EXPECT_TRUE(next.process(seq.frame(0).toFrame()).colour_resampled);
  next.newCamera();
  EXPECT_FALSE(next.colourResampling());
  EXPECT_FALSE(next.colourCheck().decided());

  Params keep;
  keep.odometry.unregistered_colour = UnregisteredColour::kAsGiven;
  Odometry as_it_comes(keep);
  for (int i = 0; i < seq.size(); ++i) {
    EXPECT_FALSE(as_it_comes.process(seq.frame(i).toFrame()).colour_resampled);
  }
  EXPECT_EQ(as_it_comes.colourCheck().verdict().state, ColourDepthCheck::State::kUnregistered);
  EXPECT_FALSE(as_it_comes.colourResampling());

  const auto registered = exactSequence(16);
  Odometry plain;
  for (int i = 0; i < registered.size(); ++i) {
    EXPECT_FALSE(plain.process(registered.frame(i).toFrame()).colour_resampled);
  }
  EXPECT_EQ(plain.colourCheck().verdict().state, ColourDepthCheck::State::kRegistered);
  EXPECT_FALSE(plain.colourResampling());
}

// Once the colour is resampled, the last level is led by the depth (CoarseToFineParams::
// depth_led): the dense plane term, off on noise in blobs as a real Kinect's, then counts fully.
// A registered camera with the same noise keeps it off.
TEST(Odometry, ColourFromASecondCameraLeavesTheLastLevelToTheDepth) {
  synth::SequenceOptions o;
  o.frames = 13;
  o.colour_focal_ratio = 0.897;
  o.depth_noise_correlation = 3.0;
  for (const bool unregistered : {true, false}) {
    SCOPED_TRACE(unregistered ? "colour from a second camera" : "registered colour");
    if (!unregistered) o.colour_focal_ratio = 1.0;
    const synth::SynthSequence seq(o);
    Odometry odo;
    odo.reset(seq.poses()[0]);
    bool resampled = false;
    for (int i = 0; i < seq.size(); ++i) {
      const OdometryResult r = odo.process(seq.frame(i).toFrame());
      resampled = resampled || r.colour_resampled;
      if (i == 0) continue;  // the first frame registers nothing
      ASSERT_EQ(r.tracking, Tracking::kOk) << i;
      ASSERT_TRUE(r.solver.coarse_to_fine);
      EXPECT_EQ(r.solver.coarse_to_fine->dense_weight, r.colour_resampled ? 1.0 : 0.0) << i;
    }
    EXPECT_EQ(resampled, unregistered);
    EXPECT_EQ(odo.describeColour().find("led by the depth") != std::string::npos, unregistered)
        << odo.describeColour();
    // The engine's parameters say so, and the colour's description names what changed.
    EXPECT_EQ(odo.engineParams().coarse_to_fine.depth_led, unregistered);
    EXPECT_EQ(odo.engineParams().coarse_to_fine.photometric, !unregistered);
    EXPECT_FALSE(odo.params().coarse_to_fine.depth_led);
    EXPECT_EQ(odo.describeColour().find("the engine's parameters now: "
                                        "coarse_to_fine/photometric=false "
                                        "coarse_to_fine/depth_led=true") != std::string::npos,
              unregistered)
        << odo.describeColour();
  }
  // With unregistered_colour resample, the colour alone: the engine as configured.
  Params resample_only;
  resample_only.odometry.unregistered_colour = UnregisteredColour::kResample;
  o.colour_focal_ratio = 0.897;
  const synth::SynthSequence seq(o);
  Odometry odo(resample_only);
  for (int i = 0; i < seq.size(); ++i) odo.process(seq.frame(i).toFrame());
  ASSERT_TRUE(odo.colourResampling());
  EXPECT_TRUE(odo.engineParams().coarse_to_fine.photometric);
  EXPECT_FALSE(odo.engineParams().coarse_to_fine.depth_led);
  EXPECT_EQ(odo.describeColour().find("engine's parameters"), std::string::npos);
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

// ---------------------------------------------------------------------------------------------
// The judgement, keyframe and re-seeding rules as functions of their inputs.

SolverResult solved(double matched,
                    const Eigen::Isometry3d& transform = Eigen::Isometry3d::Identity()) {
  SolverResult s;
  s.status = SolverStatus::kConverged;
  s.matched_fraction = matched;
  s.transform = transform;
  return s;
}

Eigen::Isometry3d moved(double metres, double degrees) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << metres, 0.0, 0.0;
  T.linear() = Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d::UnitY()).matrix();
  return T;
}

TEST(Judgement, LostHardOrOkFromTheSolverAndTheMotionPerFrame) {
  const OdometryParams p;  // lost below 10% matched, hard below 25%, 0.3 m / 20 deg per frame
  const Eigen::Isometry3d still = Eigen::Isometry3d::Identity();
  EXPECT_EQ(judgeTracking(solved(0.8), still, p).tracking, Tracking::kOk);
  EXPECT_EQ(judgeTracking(solved(0.8), still, p).message, "");
  SolverResult failed = solved(0.8);
  failed.status = SolverStatus::kTooFewPoints;
  EXPECT_EQ(judgeTracking(failed, still, p).tracking, Tracking::kLost);
  const Judgement apart = judgeTracking(solved(0.05), still, p);
  EXPECT_EQ(apart.tracking, Tracking::kLost);
  EXPECT_NE(apart.message.find("do not overlap"), std::string::npos) << apart.message;
  // The limits hold for the motion from the last frame, not for the registration's own
  // transform (a keyframe may lie further back).
  EXPECT_EQ(judgeTracking(solved(0.8, moved(0.4, 0)), still, p).tracking, Tracking::kOk);
  EXPECT_EQ(judgeTracking(solved(0.8), moved(0.4, 0), p).tracking, Tracking::kLost);
  EXPECT_EQ(judgeTracking(solved(0.8), moved(0.0, 25.0), p).tracking, Tracking::kLost);
  EXPECT_EQ(judgeTracking(solved(0.2), still, p).tracking, Tracking::kHard);
  SolverResult capped = solved(0.8);
  capped.status = SolverStatus::kMaxIterations;
  EXPECT_EQ(judgeTracking(capped, still, p).tracking, Tracking::kHard);
}

TEST(Keyframes, TakenWhenTheOverlapOrTheMotionFromTheKeyframeCrossesItsThreshold) {
  OdometryParams p;
  p.keyframe_matched_fraction = 0.6;
  p.keyframe_translation = 0.05;
  p.keyframe_rotation = 3.0;
  const Judgement ok{Tracking::kOk, ""}, hard{Tracking::kHard, "weak overlap"};
  EXPECT_FALSE(takesKeyframe(ok, solved(0.7, moved(0.04, 2.5)), p));
  EXPECT_TRUE(takesKeyframe(ok, solved(0.5, moved(0.04, 2.5)), p));
  EXPECT_TRUE(takesKeyframe(ok, solved(0.7, moved(0.06, 0.0)), p));
  EXPECT_TRUE(takesKeyframe(ok, solved(0.7, moved(0.0, 3.5)), p));
  EXPECT_TRUE(takesKeyframe(hard, solved(0.7), p));
}

TEST(Keyframes, ALostFrameReplacesTheReferenceOnlyWhenItShould) {
  Params keyframe;
  keyframe.odometry.reference = Reference::kKeyframe;
  Params previous;
  previous.odometry.reference = Reference::kPreviousFrame;
  const SolverResult noise = solved(0.0), narrow = solved(0.08);
  for (const Params& p : {keyframe, previous}) {
    EXPECT_FALSE(replacesReference(narrow, 10, 3000, 2, p)) << "a blank frame never does";
    EXPECT_TRUE(replacesReference(narrow, 3000, 10, 1, p)) << "a blank reference always is";
    EXPECT_TRUE(replacesReference(noise, 3000, 3000, 2, p)) << "the second lost in a row";
  }
  // Keyframes: the first lost frame is followed by a try against the last good keyframe.
  EXPECT_FALSE(replacesReference(narrow, 3000, 3000, 1, keyframe));
  // Frame to frame: a narrowly lost frame re-seeds, a first frame of noise does not.
  EXPECT_TRUE(replacesReference(narrow, 3000, 3000, 1, previous));
  EXPECT_FALSE(replacesReference(noise, 3000, 3000, 1, previous));
}

TEST(Covariance, OfAMotionIsTheScaledInverseCurvatureAndNoneWhenADirectionIsFree) {
  SolverResult s = solved(0.8);
  s.hessian = -Matrix6d::Identity() * 4.0;
  s.hessian(5, 5) = -16.0;
  s.nnz = 6000;
  Params params;
  params.coarse_to_fine.covariance_scale = 2.0;
  const auto coarse_to_fine = makeRegistrationEngine(params);
  const std::optional<Matrix6d> c = coarse_to_fine->covariance(s, 3000);
  ASSERT_TRUE(c);
  EXPECT_NEAR((*c)(0, 0), 0.5, 1e-12);  // 2 / 4
  EXPECT_NEAR((*c)(5, 5), 0.125, 1e-12);
  // The paper's engine: times the kernel pairs per moving point (2 here).
  params.registration.engine = Engine::kPaper;
  params.paper.covariance_scale = 2.0;
  const std::optional<Matrix6d> paper = makeRegistrationEngine(params)->covariance(s, 3000);
  ASSERT_TRUE(paper);
  EXPECT_NEAR((*paper)(0, 0), 1.0, 1e-12);
  s.hessian(2, 2) = 0.0;  // nothing constrains rotation about z
  EXPECT_FALSE(coarse_to_fine->covariance(s, 3000));
  s.hessian(2, 2) = std::nan("");
  EXPECT_FALSE(coarse_to_fine->covariance(s, 3000));
}

TEST(Covariance, LostGrowthIsWhatTheCameraCanMoveUnseen) {
  OdometryParams p;
  p.lost_speed = 1.0;
  p.lost_angular_speed = 90.0;
  const Matrix6d g = lostGrowth(0.5, p);
  EXPECT_NEAR(g(0, 0), std::pow(M_PI / 4.0, 2), 1e-12);  // 45 deg in 0.5 s
  EXPECT_NEAR(g(5, 5), 0.25, 1e-12);                     // 0.5 m
  EXPECT_EQ(g(0, 3), 0.0);
  EXPECT_EQ(lostGrowth(-1.0, p), Matrix6d::Zero());
  // Rotating a covariance into other axes keeps each block's trace.
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << 1e-4, 0, 0, 4e-6, 0, 0;
  const Eigen::Matrix3d quarter = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).matrix();
  const Matrix6d r = rotateCovariance(c, quarter);
  EXPECT_NEAR(r(1, 1), 1e-4, 1e-15);
  EXPECT_NEAR(r(4, 4), 4e-6, 1e-15);
  Matrix6d bad = c;
  bad(2, 2) = std::nan("");
  EXPECT_EQ(sanitiseCovariance(bad), lostCovariance());
}

// ---------------------------------------------------------------------------------------------
// Keyframe odometry on exact sequences.

Params keyframeParams() {
  Params p;
  p.odometry.reference = Reference::kKeyframe;
  return p;
}

// At 320x240: these tests run many registrations, also under the sanitizers.
synth::SynthSequence exactSequence(int frames, synth::MotionKind motion) {
  synth::SequenceOptions o;
  o.frames = frames;
  o.noise = false;
  o.motion = motion;
  o.camera = synth::scaledDefaultCamera(320, 240);
  return synth::SynthSequence(o);
}

// Moving away from the start (xyz: along the camera's x at 1 cm per frame): the first frame is
// the keyframe until a frame has moved beyond keyframe_translation from it, or until its overlap
// drops below keyframe_matched_fraction; that frame is the next keyframe.
TEST(Keyframes, ANewKeyframeIsTakenWhereTheMotionOrTheOverlapCrossesItsThreshold) {
  const auto seq = exactSequence(16, synth::MotionKind::kXyz);
  for (int criterion = 0; criterion < 2; ++criterion) {
    Params p = keyframeParams();
    p.odometry.keyframe_rotation = 90.0;
    p.odometry.keyframe_translation = criterion == 0 ? 0.045 : 10.0;
    p.odometry.keyframe_matched_fraction = criterion == 0 ? 0.0 : 0.9;
    Odometry odo(p);
    odo.reset(seq.poses()[0]);
    int switched = -1;
    for (int i = 0; i < seq.size() && switched < 0; ++i) {
      const OdometryResult r = odo.process(seq.frame(i).toFrame());
      ASSERT_NE(r.tracking, Tracking::kLost) << i << ": " << r.message;
      EXPECT_EQ(r.frame_index, std::uint64_t(i));
      EXPECT_EQ(r.keyframe_index, 0u) << i;
      const double from_start = (seq.poses()[0].inverse() * seq.poses()[i]).translation().norm();
      if (i > 0 && r.new_keyframe) {
        switched = i;
        if (criterion == 0) {
          EXPECT_GT(from_start, 0.045 - 1.5e-3);
        } else {
          EXPECT_LT(r.solver.matched_fraction, 0.9);
        }
      } else if (i > 0) {
        if (criterion == 0) {
          EXPECT_LT(from_start, 0.045 + 1.5e-3) << i;
        } else {
          EXPECT_GE(r.solver.matched_fraction, 0.9) << i;
        }
      }
    }
    std::printf("  criterion %s: the first new keyframe is frame %d\n",
                criterion == 0 ? "translation 4.5 cm" : "matched 90%", switched);
    ASSERT_GT(switched, 1);
    const OdometryResult next = odo.process(seq.frame(switched + 1).toFrame());
    EXPECT_EQ(next.keyframe_index, std::uint64_t(switched));
    EXPECT_LT(translationError(seq.poses()[switched + 1], next.pose), 1.5e-3 * (switched + 1));
  }
}

// The frame after a lost one is registered to the keyframe in use before the loss, not to the
// lost frame, and lands where it belongs.
TEST(Keyframes, TheFrameAfterALostOneIsRegisteredToTheLastGoodKeyframe) {
  const auto seq = exactSequence(6);
  Odometry odo(keyframeParams());
  odo.reset(seq.poses()[0]);
  OdometryResult r;
  for (int i = 0; i < 4; ++i) r = odo.process(seq.frame(i).toFrame());
  const std::uint64_t keyframe = r.new_keyframe ? r.frame_index : r.keyframe_index;
  Frame noise = seq.frame(4).toFrame();
  cv::RNG rng(11);
  rng.fill(noise.color, cv::RNG::UNIFORM, 0, 256);
  rng.fill(noise.depth, cv::RNG::UNIFORM, 0.5, 4.0);
  const OdometryResult lost = odo.process(noise);
  EXPECT_EQ(lost.tracking, Tracking::kLost);
  EXPECT_FALSE(lost.new_keyframe);
  EXPECT_TRUE(lost.pose.isApprox(r.pose));
  EXPECT_GT(lost.pose_covariance(3, 3), r.pose_covariance(3, 3)) << "the held pose may be wrong";
  const OdometryResult back = odo.process(seq.frame(5).toFrame());
  EXPECT_TRUE(back.tracking == Tracking::kOk || back.tracking == Tracking::kHard)
      << toString(back.tracking) << ": " << back.message;
  EXPECT_EQ(back.keyframe_index, keyframe);
  EXPECT_LT(translationError(seq.poses()[5], back.pose), 1.5e-3 * 5);
  EXPECT_LT(rotationErrorDeg(seq.poses()[5], back.pose), 0.1 * 5);
  // Its covariance is the keyframe's plus one registration again: the loss left no trace.
  EXPECT_LT(back.pose_covariance(3, 3), lost.pose_covariance(3, 3));
}

// A frame that no longer matches its keyframe well enough (here: lost below 85% matched, the
// keyframe kept whatever the motion) is registered to the last tracked frame, which becomes
// the keyframe: the camera moves on without a lost frame.
TEST(Keyframes, AFrameThatFailsAgainstItsKeyframeFallsBackToTheLastTrackedFrame) {
  const auto seq = exactSequence(30, synth::MotionKind::kXyz);
  Params p = keyframeParams();
  p.odometry.keyframe_translation = 10.0;
  p.odometry.keyframe_rotation = 180.0;
  p.odometry.keyframe_matched_fraction = 0.0;
  p.odometry.lost_matched_fraction = 0.85;
  p.odometry.hard_matched_fraction = 0.85;
  Odometry odo(p);
  odo.reset(seq.poses()[0]);
  int fell_back = 0;
  for (int i = 0; i < seq.size(); ++i) {
    const OdometryResult r = odo.process(seq.frame(i).toFrame());
    ASSERT_NE(r.tracking, Tracking::kLost) << "frame " << i << ": " << r.message;
    if (r.fell_back_to_previous) {
      ++fell_back;
      EXPECT_EQ(r.keyframe_index, std::uint64_t(i - 1));
    }
    EXPECT_LT(translationError(seq.poses()[i], r.pose), 1.5e-3 * (i + 1)) << i;
  }
  std::printf("  %d of %d frames fell back to the last tracked frame\n", fell_back, seq.size());
  EXPECT_GE(fell_back, 1);
}

// A still camera: each frame is registered to the same keyframe, so the pose covariance is the
// keyframe's plus one registration's, frame after frame; frame to frame it is a sum that grows
// with every frame.
TEST(Keyframes, PoseCovarianceGrowsPerKeyframeNotPerFrame) {
  const auto seq = exactSequence(12, synth::MotionKind::kStill);
  // Per mode: the pose covariance's trace at frame 1 and at the last frame, and the trace of
  // one registration's covariance (frame 1's).
  double first[2] = {0, 0}, last[2] = {0, 0}, registration[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    Params p = keyframeParams();
    if (k == 1) p.odometry.reference = Reference::kPreviousFrame;
    Odometry odo(p);
    for (int i = 0; i < seq.size(); ++i) {
      const OdometryResult r = odo.process(seq.frame(i).toFrame());
      const double trace = r.pose_covariance.trace();
      if (i == 1) {
        first[k] = trace;
        registration[k] = r.registration_covariance.trace();
      }
      last[k] = trace;
    }
  }
  std::printf(
      "  pose covariance trace, frame 1 -> 11: keyframe %.4g -> %.4g, previous frame "
      "%.4g -> %.4g (one registration's: %.3g, %.3g)\n",
      first[0], last[0], first[1], last[1], registration[0], registration[1]);
  // Measured: against its keyframe each frame adds nothing (6.061e-9 both, the first frame's
  // own covariance); frame to frame each of the 10 registrations adds its 6.14e-11.
  ASSERT_GT(registration[1], 0.0);
  EXPECT_LT(last[0] - first[0], 0.5 * registration[0]);
  EXPECT_GT(last[1] - first[1], 8.0 * registration[1]);
}

}  // namespace
}  // namespace acvo
