// Whole rendered sequences under what a real camera does to its images, each model of the
// camera against the default with it turned off: colour and depth of different instants, auto
// exposure, motion blur, depth noise in blobs, colour from a second camera, vignetting. Bounds
// are the figures measured here, with a margin.
#include <array>
#include <cstdio>

#include <gtest/gtest.h>

#include "sequence_support.hpp"

namespace acvo {
namespace {

using namespace acvo::test;  // the sequences' helpers (sequence_support.hpp)

// Colour taken 12 ms after the depth (unsynchronised streams, as a Kinect v1's or a
// RealSense's), the camera at 0.5 m/s: the poses are the colour's, and each frame's depth is
// moved to the colour's time (OdometryParams::sync_depth) by the last frame-to-frame motion, then
// again, before the finest level, by the frame's own motion as the coarse levels found it.
// Without it each point's colour is of another instant than its position.
TEST(Sequences, UnsynchronisedColourAndDepthAreBroughtToOneInstant) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.seed = 2;
  o.speed = 0.5;
  o.colour_delay = 0.012;
  const synth::SynthSequence seq(o);
  Trajectory gt;  // at the colour's stamps
  for (int i = 0; i < seq.size(); ++i) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", seq.stamp(i) + o.colour_delay);
    gt.push_back({text, seq.stamp(i) + o.colour_delay, seq.colourPose(i)});
  }
  Params unsynced;
  unsynced.odometry.sync_depth = SyncDepth::kNone;
  // Measured 0.00022 m/s, 0.0057 deg/s moved and 0.00182, 0.0251 as it came (with one keyframe
  // and no window: 0.00036, 0.0078 and 0.01509, 0.5213; 150 frames of the same motion without
  // the delay: 0.0003, 0.008; moved by the last frame's motion alone, last_motion: 0.00055,
  // 0.0079).
  expectTheModelHelps(seq, gt, Params(), unsynced, "depth moved to the colour's time",
                      "depth as it came", {0.00022, 0.0057}, 3.0);
}

// A camera's auto exposure: the colour's brightness swings by up to +-20%, 2% a frame
// (SequenceOptions::brightness_swing). The photometric term compares grey values at the gain it
// measures between each frame and its reference (CoarseToFineParams::photometric_gain); without
// it every grey value is off by the gain, and the motion with it.
TEST(Sequences, AutoExposureIsMeasuredNotMistakenForMotion) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.brightness_swing = 0.2;
  const synth::SynthSequence seq(o);
  Params as_they_are = colourModelBase();
  as_they_are.coarse_to_fine.photometric_gain = false;
  // Measured (the dense term off: colourModelBase) 0.00021 m/s, 0.0044 deg/s at the gain and
  // 0.00088, 0.0230 as they are (with one keyframe and no window: 0.00039, 0.0074 and 0.00117,
  // 0.0255; 150 frames of this room without the swing, scripts/results: 0.0004, 0.008).
  expectTheModelHelps(seq, groundtruthOf(seq), colourModelBase(), as_they_are,
                      "grey values at the measured gain", "grey values as they are",
                      {0.00021, 0.0044}, 2.0);
}

// Motion blur where the colour has no texture: every colour edge is a depth edge, and a blurred
// edge gives the points beside it, on either surface, the other surface's colour. The default
// leaves out the points whose smear over the exposure (CoarseToFineParams::exposure_time, as
// predicted from the last motion) crosses a depth edge; with sharp images assumed they pull
// the motion.
TEST(Sequences, MotionBlurOverDepthEdgesIsNotMistakenForMotion) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.texture = false;
  o.blur = true;
  const synth::SynthSequence seq(o);
  Params sharp = colourModelBase();
  sharp.coarse_to_fine.exposure_time = 0.0;
  // Measured (the dense term off: colourModelBase) 0.00108 m/s, 0.0255 deg/s at the default
  // 0.016 s (the renderer blurs over 1/60 s) and 0.00264, 0.0650 with sharp images assumed.
  expectTheModelHelps(seq, groundtruthOf(seq), colourModelBase(), sharp,
                      "blur over the exposure time", "blur assumed away", {0.00108, 0.0255}, 2.0);
}

// A real Kinect's depth errs in blobs of neighbouring pixels (scripts/depth_noise: as a 3-px
// correlation length). Averaging over many pixels does not undo such errors, so a method whose
// precision came from per-pixel noise would lose it; acvo's must not. The room without texture,
// where the depth carries most: the same frames with the noise per pixel and in blobs. The dense
// depth term averages windows of pixels: it gains on the first and stays off on the second.
TEST(Sequences, DepthNoiseInBlobsAsARealKinectsCostsLittle) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.texture = false;
  const synth::SynthSequence per_pixel(o);
  o.depth_noise_correlation = 3.0;
  const synth::SynthSequence blobs(o);
  const Trajectory gt = groundtruthOf(per_pixel);
  ASSERT_EQ(gt.back().pose.matrix(), groundtruthOf(blobs).back().pose.matrix());
  Params sparse;
  sparse.coarse_to_fine.dense_point_to_plane = false;
  const auto a = runPolicies<2>(
      {Params(), sparse}, per_pixel.size(), [&](int i) { return per_pixel.frame(i).toFrame(); },
      gt);
  const auto b = runPolicies<2>(
      {Params(), sparse}, blobs.size(), [&](int i) { return blobs.frame(i).toFrame(); }, gt);
  std::printf(
      "  noise per pixel: RPE %.5f m/s %.4f deg/s (without the dense term %.5f, %.4f); "
      "in blobs: %.5f m/s %.4f deg/s (%.5f, %.4f)\n",
      a[0].rpe.trans.rmse, a[0].rpe.rot_deg.rmse, a[1].rpe.trans.rmse, a[1].rpe.rot_deg.rmse,
      b[0].rpe.trans.rmse, b[0].rpe.rot_deg.rmse, b[1].rpe.trans.rmse, b[1].rpe.rot_deg.rmse);
  for (int p = 0; p < 2; ++p) {
    EXPECT_EQ(a[p].lost, 0);
    EXPECT_EQ(b[p].lost, 0);
  }
  // Measured: per pixel 0.00039 m/s, 0.0118 deg/s (without the dense term 0.00093, 0.0204); in
  // blobs 0.00093, 0.0210 either way (with one keyframe and no window: 0.00075, 0.0173 (0.00120,
  // 0.0239) and 0.00120, 0.0257; with the photometric term's forward direction alone as well,
  // reverse_photometric off: 0.00080, 0.0174 (0.00156, 0.0258) and 0.00158, 0.0282).
  EXPECT_LT(b[0].rpe.trans.rmse, 1.3 * 0.00093);
  EXPECT_LT(b[0].rpe.rot_deg.rmse, 1.3 * 0.0210);
  EXPECT_LT(a[0].rpe.trans.rmse, 1.3 * 0.00039);
  EXPECT_LT(a[0].rpe.rot_deg.rmse, 1.3 * 0.0118);
  // Blobs cost the selected points little against noise per pixel.
  EXPECT_LT(b[0].rpe.trans.rmse, 1.3 * a[1].rpe.trans.rmse);
  EXPECT_LT(b[0].rpe.rot_deg.rmse, 1.3 * a[1].rpe.rot_deg.rmse);
  // The dense term is off in blobs (the same figures to the last digit), and on per pixel cuts
  // the error by about half (measured 0.42x, 0.58x; with one keyframe and no window 0.63x, 0.72x,
  // and 0.51x, 0.67x with the grey values read in one direction only).
  EXPECT_EQ(b[0].rpe.trans.rmse, b[1].rpe.trans.rmse);
  EXPECT_LT(a[0].rpe.trans.rmse, 0.7 * a[1].rpe.trans.rmse);
  EXPECT_LT(a[0].rpe.rot_deg.rmse, 0.8 * a[1].rpe.rot_deg.rmse);
}

// Colour from a second camera, as 7-Scenes' (a Kinect's raw depth paired with its colour): 0.897
// times the depth camera's focal length, 2.5 cm beside it, the depth's noise in blobs. Once the
// colour check judges it unregistered (at the tenth frame, 1.4x: too little for the early
// verdict's 1.5x), each frame's colour is resampled to the depth camera by the focal ratio it
// found, the photometric term is left out (the baseline's offset remains) and the last level
// is led by the depth; as it came, the points chosen at the colour's edges sit where the
// texture appears, which slides along the surfaces with the motion.
TEST(Sequences, ColourFromASecondCameraIsResampledToTheDepthCamera) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.seed = 31;
  o.speed = 0.5;
  o.colour_focal_ratio = 0.897;
  o.colour_baseline = 0.025;
  o.depth_noise_correlation = 3.0;
  const synth::SynthSequence seq(o);
  Params as_it_came;
  as_it_came.odometry.unregistered_colour = UnregisteredColour::kAsGiven;
  const auto runs = runPolicies<2>(
      {Params(), as_it_came}, seq.size(),
      [&](int i) { return seq.frame(i).toFrame(); }, groundtruthOf(seq));
  std::printf(
      "  colour resampled: RPE %.5f m/s %.4f deg/s; as it came: %.5f m/s %.4f deg/s\n",
      runs[0].rpe.trans.rmse, runs[0].rpe.rot_deg.rmse, runs[1].rpe.trans.rmse,
      runs[1].rpe.rot_deg.rmse);
  for (const auto& run : runs) EXPECT_EQ(run.lost, 0);
  // Measured 0.00559 m/s, 0.2585 deg/s resampled, 0.02185, 0.5670 as it came (with one keyframe
  // and no window: 0.00701, 0.2303 and 0.02311, 0.5356; with the colour registered before the
  // first frame as well, 0.0047 / 0.036: most of the rotation error is the first ten frames').
  EXPECT_LT(runs[0].rpe.trans.rmse, 1.3 * 0.00559);
  EXPECT_LT(runs[0].rpe.rot_deg.rmse, 1.3 * 0.2585);
  EXPECT_GT(runs[1].rpe.trans.rmse, 3.0 * runs[0].rpe.trans.rmse);
  EXPECT_GT(runs[1].rpe.rot_deg.rmse, 1.8 * runs[0].rpe.rot_deg.rmse);
}

// A lens's vignetting: the colour darkens by exp(-1 rho) towards the corners (43% at a corner),
// so a point's grey value changes as it crosses the image. The photometric term measures it per
// registration (CoarseToFineParams::photometric_vignetting); without it the residuals carry
// the falloff as if it were motion.
TEST(Sequences, VignettingIsMeasuredNotMistakenForMotion) {
  synth::SequenceOptions o;
  o.frames = 120;
  o.vignetting = -1.0;
  const synth::SynthSequence seq(o);
  Params without = colourModelBase();
  without.coarse_to_fine.photometric_vignetting = false;
  // Measured (the dense term off: colourModelBase) 0.00024 m/s, 0.0051 deg/s measured and
  // 0.00074, 0.0137 not modelled.
  expectTheModelHelps(seq, groundtruthOf(seq), colourModelBase(), without, "vignetting measured",
                      "vignetting not modelled", {0.00024, 0.0051}, 1.5);
}

}  // namespace
}  // namespace acvo
