// Synthetic scenes and rendering: exact geometry, determinism, the scene variants, the
// Kinect-like degradations, motion blur and an unregistered colour camera.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include <Eigen/SVD>
#include <opencv2/imgproc.hpp>

#include "synth/layout.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "synth/sequence.hpp"
#include "synth/trajectory.hpp"

namespace acvo::synth {
namespace {

// How far `p` is from surface `id` of `scene` (0 on it), computed from the primitive's
// definition alone: plane distance, plus how far it lies outside the face's bounds.
double distanceToSurface(const Scene& scene, int id, const Eigen::Vector3d& p) {
  const int quads = static_cast<int>(scene.quads.size());
  if (id < quads) {
    const Quad& q = scene.quads[id];
    const Eigen::Vector3d r = p - q.centre;
    const double outside =
        std::max({0.0, std::abs(r.dot(q.axis_s)) - q.half_s, std::abs(r.dot(q.axis_t)) - q.half_t});
    return std::abs(r.dot(q.normal())) + outside;
  }
  const Box& box = scene.boxes[(id - quads) / 6];
  const int face = (id - quads) % 6, axis = face / 2;
  const double side = face % 2 ? 1.0 : -1.0;
  const Eigen::Vector3d local = box.box_to_world.inverse() * p;
  double outside = 0.0;
  for (int i = 0; i < 3; ++i)
    if (i != axis) outside = std::max(outside, std::abs(local[i]) - box.half_size[i]);
  return std::abs(local[axis] - side * box.half_size[axis]) + outside;
}

RenderOptions exactOptions() {
  return RenderOptions{};
}  // default camera, no noise

Eigen::Isometry3d somePose(int frame, std::uint64_t seed = 1) {
  MotionOptions m;
  m.frames = 301;
  m.seed = seed;
  return Motion(m).poseAt(frame / 30.0);
}

cv::Mat grey(const cv::Mat& bgr) {
  cv::Mat g;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  return g;
}

// Central-difference gradient magnitude of the grey image, as a point selector sees it.
cv::Mat gradientMagnitude(const cv::Mat& bgr) {
  cv::Mat g, gx, gy, mag;
  grey(bgr).convertTo(g, CV_32F);
  const cv::Mat kx = (cv::Mat_<float>(1, 3) << -0.5f, 0.0f, 0.5f);
  cv::filter2D(g, gx, -1, kx);
  cv::filter2D(g, gy, -1, kx.t());
  cv::magnitude(gx, gy, mag);
  return mag;
}

TEST(SynthRender, NoiseFreeBackProjectionLandsOnTheSurfaceSeen) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const Scene scene = makeScene({true, true, seed});
    for (int frame : {0, 100, 250}) {
      const Eigen::Isometry3d pose = somePose(frame, seed);
      const SynthFrame f = render(scene, pose, exactOptions());
      int checked = 0;
      double worst_surface = 0.0, worst_ray = 0.0;
      for (int v = 0; v < f.camera.height; v += 7) {
        for (int u = 0; u < f.camera.width; u += 5) {
          const float d = f.depth_m.at<float>(v, u);
          ASSERT_GT(d, 0.0f) << "a ray escaped the closed room at " << u << "," << v;
          const Eigen::Vector3d world = pose * f.camera.backProject(u, v, d);
          const int id = f.surface.at<int>(v, u);
          worst_surface = std::max(worst_surface, distanceToSurface(scene, id, world));
          // Re-intersect along a unit-length ray: the nearest hit must be this point.
          Ray ray;
          ray.origin = pose.translation();
          ray.direction = (world - ray.origin).normalized();
          Hit hit;
          ASSERT_TRUE(intersect(scene, ray, &hit));
          worst_ray = std::max(worst_ray, (hit.point - world).norm());
          ++checked;
        }
      }
      EXPECT_GT(checked, 8000);
      EXPECT_LT(worst_surface, 1e-3) << "seed " << seed << " frame " << frame;
      EXPECT_LT(worst_ray, 1e-3) << "seed " << seed << " frame " << frame;
    }
  }
}

TEST(SynthRender, PixelCentresAndOpticalAxes) {
  // Camera 1 m in front of the single plane, looking straight at it along world +y, with
  // the principal point on a pixel centre: image x is world +x, image y is world -z.
  const Scene scene = makeScene({false, true, 1});
  const Eigen::Isometry3d pose = lookAt({0, kSinglePlaneY - 1.0, 1}, {0, kSinglePlaneY, 1});
  RenderOptions options;
  options.camera.fx = options.camera.fy = 100.0;
  options.camera.cx = 320.0;
  options.camera.cy = 240.0;
  const SynthFrame f = render(scene, pose, options);
  auto world = [&](int u, int v) {
    return Eigen::Vector3d(pose * f.camera.backProject(u, v, f.depth_m.at<float>(v, u)));
  };
  EXPECT_NEAR(f.depth_m.at<float>(240, 320), 1.0, 1e-6);
  EXPECT_LT((world(320, 240) - Eigen::Vector3d(0, kSinglePlaneY, 1)).norm(), 1e-6);
  EXPECT_NEAR(f.depth_m.at<float>(240, 420), 1.0, 1e-6);  // 45 degrees right
  EXPECT_LT((world(420, 240) - Eigen::Vector3d(1, kSinglePlaneY, 1)).norm(), 1e-6);
  EXPECT_LT((world(320, 340) - Eigen::Vector3d(0, kSinglePlaneY, 0)).norm(), 1e-6);  // down
}

// An unregistered colour camera. Its image is the one a camera with its intrinsics at its
// place renders; depth, surfaces and the pose stay the depth camera's. Where it looks, in the
// flat-coloured room (colour changes only where the surface does): at half the focal length,
// colour pixel c + k sees what pixel c + 2k of the registered image sees; 1 m from the single
// plane, 0.1 m along x at fx 100, colour pixel u sees the point pixel u + 10 sees (the same
// texture, filtered for the colour camera's own pixel footprint).
TEST(SynthRender, AnUnregisteredColourCameraSeesFromItsOwnPlace) {
  RenderOptions registered;
  registered.camera.fx = registered.camera.fy = 100.0;
  registered.camera.cx = 320.0;
  registered.camera.cy = 240.0;
  struct Case {
    Scene scene;
    Eigen::Isometry3d pose;
    double ratio, baseline;
    int du, scale;  // where colour pixel (u, v) looks in the registered image
  };
  const Case cases[] = {
      {makeScene({true, false, 3}), somePose(40, 3), 0.5, 0.0, 0, 2},
      {makeScene({false, true, 1}),
       lookAt({0, kSinglePlaneY - 1.0, 1}, {0, kSinglePlaneY, 1}), 1.0, 0.1, 10, 1}};
  for (const Case& c : cases) {
    const SynthFrame reference = render(c.scene, c.pose, registered);
    const cv::Mat ref = grey(reference.bgr);
    RenderOptions colour = registered;
    colour.colour_focal_ratio = c.ratio;
    colour.colour_baseline = c.baseline;
    ASSERT_FALSE(colour.colourRegistered());
    const SynthFrame f = render(c.scene, c.pose, colour);
    EXPECT_EQ(cv::norm(f.depth_m, reference.depth_m, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::countNonZero(f.surface != reference.surface), 0);
    EXPECT_TRUE(f.pose.isApprox(c.pose));
    RenderOptions there = registered;
    there.camera = colour.colourCamera();
    const SynthFrame seen = render(c.scene, colour.colourPose(c.pose), there);
    EXPECT_EQ(cv::norm(f.bgr, seen.bgr, cv::NORM_INF), 0.0);
    EXPECT_LT(((c.pose.inverse() * colour.colourPose(c.pose)).translation() -
               Eigen::Vector3d(c.baseline, 0, 0))
                  .norm(),
              1e-12);

    // Mean absolute grey difference of the colour image against the registered one, unmoved
    // and where each pixel looks, over the pixels that look inside the image.
    const cv::Mat g = grey(f.bgr);
    double unmoved = 0.0, moved = 0.0;
    int n = 0;
    for (int v = 0; v < 480; v += 2) {
      for (int u = 0; u < 640; u += 2) {
        const int x = 320 + c.scale * (u - 320) + c.du, y = 240 + c.scale * (v - 240);
        if (x < 0 || x >= 640 || y < 0 || y >= 480) continue;
        unmoved += std::abs(double(g.at<std::uint8_t>(v, u)) - ref.at<std::uint8_t>(v, u));
        moved += std::abs(double(g.at<std::uint8_t>(v, u)) - ref.at<std::uint8_t>(y, x));
        ++n;
      }
    }
    unmoved /= n, moved /= n;
    std::printf("focal x%.1f, baseline %.1f m: mean grey difference %.2f unmoved, %.2f where "
                "it looks\n", c.ratio, c.baseline, unmoved, moved);
    EXPECT_GT(unmoved, 5.0);
    EXPECT_LT(moved, 0.1 * unmoved);
  }
}

TEST(SynthRender, DeterministicForASeed) {
  RenderOptions noisy;
  noisy.noise = true;
  const Eigen::Isometry3d pose = somePose(40);
  const SynthFrame a = render(makeScene({true, true, 5}), pose, noisy, 11);
  const SynthFrame b = render(makeScene({true, true, 5}), pose, noisy, 11);
  EXPECT_EQ(cv::norm(a.bgr, b.bgr, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.depth_m, b.depth_m, cv::NORM_INF), 0.0);

  const SynthFrame other_scene = render(makeScene({true, true, 6}), pose, noisy, 11);
  EXPECT_GT(cv::norm(a.bgr, other_scene.bgr, cv::NORM_L1) / a.bgr.total(), 5.0);
  const SynthFrame other_noise = render(makeScene({true, true, 5}), pose, noisy, 12);
  EXPECT_GT(cv::countNonZero(a.depth_m != other_noise.depth_m), 10000);
  EXPECT_GT(cv::norm(a.bgr, other_noise.bgr, cv::NORM_L1), 0.0);
}

// Fits a plane to the valid back-projected points; returns the largest point-plane distance.
double planeFitResidual(const SynthFrame& f, double* rms) {
  std::vector<Eigen::Vector3d> points;
  for (int v = 0; v < f.camera.height; v += 2)
    for (int u = 0; u < f.camera.width; u += 2)
      if (const float d = f.depth_m.at<float>(v, u); d > 0)
        points.push_back(f.camera.backProject(u, v, d));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= points.size();
  Eigen::MatrixXd centred(points.size(), 3);
  for (std::size_t i = 0; i < points.size(); ++i) centred.row(i) = (points[i] - mean).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinV);
  const Eigen::Vector3d normal = svd.matrixV().col(2);
  double worst = 0.0, sum = 0.0;
  for (const auto& p : points) {
    const double r = std::abs(normal.dot(p - mean));
    worst = std::max(worst, r), sum += r * r;
  }
  *rms = std::sqrt(sum / points.size());
  return worst;
}

TEST(SynthScene, StructureOffIsOnePlaneFillingTheView) {
  for (int frame : {0, 150, 299}) {
    const SynthFrame f = render(makeScene({false, true, 3}), somePose(frame, 3), exactOptions());
    EXPECT_EQ(cv::countNonZero(f.depth_m > 0), static_cast<int>(f.depth_m.total()));
    double rms = 0.0;
    EXPECT_LT(planeFitResidual(f, &rms), 1e-3);
  }
}

TEST(SynthScene, StructureOnIsNotPlanar) {
  const SynthFrame f = render(makeScene({true, true, 3}), somePose(0, 3), exactOptions());
  double rms = 0.0;
  planeFitResidual(f, &rms);
  EXPECT_GT(rms, 0.1);
  // Several surfaces in view.
  double lo = 0, hi = 0;
  cv::minMaxLoc(f.surface, &lo, &hi);
  EXPECT_GT(hi - lo, 5.0);
}

TEST(SynthScene, TextureOffGradientsOnlyAtSurfaceBoundaries) {
  const Scene scene = makeScene({true, false, 4});
  for (int frame : {0, 120}) {
    const SynthFrame f = render(scene, somePose(frame, 4), exactOptions());
    int zero = 0, total = 0, unexplained = 0;
    for (int v = 0; v + 1 < f.bgr.rows; ++v) {
      for (int u = 0; u + 1 < f.bgr.cols; ++u) {
        const cv::Vec3b c = f.bgr.at<cv::Vec3b>(v, u);
        const bool flat = c == f.bgr.at<cv::Vec3b>(v, u + 1) && c == f.bgr.at<cv::Vec3b>(v + 1, u);
        const int s = f.surface.at<int>(v, u);
        const bool boundary = s != f.surface.at<int>(v, u + 1) || s != f.surface.at<int>(v + 1, u);
        zero += flat;
        unexplained += !flat && !boundary;
        ++total;
      }
    }
    EXPECT_EQ(unexplained, 0);
    EXPECT_GT(zero, 0.97 * total) << "boundaries should be thin lines";
  }
  // No structure and no texture: one uniform colour, nothing to track.
  const SynthFrame blank = render(makeScene({false, false, 4}), somePose(60, 4), exactOptions());
  EXPECT_EQ(cv::countNonZero(gradientMagnitude(blank.bgr) > 0), 0);
}

TEST(SynthScene, TextureOnHasStrongGradientsEverywhere) {
  for (bool structure : {true, false}) {
    const SynthFrame f = render(makeScene({structure, true, 2}), somePose(30, 2), exactOptions());
    const cv::Mat mag = gradientMagnitude(f.bgr);
    EXPECT_GT(cv::countNonZero(mag > 8.0), 15000) << "structure " << structure;
    // Spread over the image: every 80x80 block has some strong gradients.
    for (int v = 0; v + 80 <= mag.rows; v += 80)
      for (int u = 0; u + 80 <= mag.cols; u += 80)
        EXPECT_GT(cv::countNonZero(mag(cv::Rect(u, v, 80, 80)) > 4.0), 50)
            << "block " << u << "," << v << " structure " << structure;
  }
}

TEST(SynthNoise, DepthNoiseGrowsWithDepthAndEdgesDropOut) {
  const Scene scene = makeScene({true, true, 1});
  const Eigen::Isometry3d pose = defaultStartPose();
  RenderOptions noisy;
  noisy.noise = true;
  const SynthFrame exact = render(scene, pose, exactOptions());
  const SynthFrame f = render(scene, pose, noisy, 3);

  // Error statistics in a near and a far depth band.
  struct Band {
    double lo, hi, sum2 = 0;
    int n = 0;
  } bands[2] = {{1.6, 2.0}, {2.9, 3.4}};
  int edge_pixels = 0, edge_dropped = 0, interior = 0, interior_valid = 0;
  for (int v = 1; v + 1 < f.camera.height; ++v) {
    for (int u = 1; u + 1 < f.camera.width; ++u) {
      const float z = exact.depth_m.at<float>(v, u), zn = f.depth_m.at<float>(v, u);
      float jump = 0.0f;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
          jump = std::max(jump, std::abs(exact.depth_m.at<float>(v + dv, u + du) - z));
      if (jump > 0.3f) {
        ++edge_pixels, edge_dropped += zn == 0.0f;
        continue;
      }
      if (jump > 0.05f) continue;
      ++interior, interior_valid += zn > 0.0f;
      for (Band& b : bands)
        if (zn > 0 && z >= b.lo && z < b.hi) b.sum2 += (zn - z) * (zn - z), ++b.n;
    }
  }
  ASSERT_GT(bands[0].n, 5000);
  ASSERT_GT(bands[1].n, 5000);
  const double near_std = std::sqrt(bands[0].sum2 / bands[0].n);
  const double far_std = std::sqrt(bands[1].sum2 / bands[1].n);
  const KinectNoise model;
  EXPECT_GT(near_std, model.depthSigma(1.6));
  EXPECT_LT(near_std, 2.0 * model.depthSigma(2.0));
  EXPECT_GT(far_std, 2.2 * near_std) << "near " << near_std << " far " << far_std;
  EXPECT_GT(edge_pixels, 500);
  EXPECT_EQ(edge_dropped, edge_pixels);
  EXPECT_GT(interior_valid, 0.99 * interior);
  // Depth is stored in 1/5000 m steps, like a TUM PNG.
  for (int v = 0; v < f.camera.height; v += 13)
    for (int u = 0; u < f.camera.width; u += 11) {
      const double raw = f.depth_m.at<float>(v, u) * 5000.0;
      EXPECT_NEAR(raw, std::round(raw), 0.01);  // float rounding of metres
    }
  // Small colour noise.
  const double mean_abs = cv::norm(f.bgr, exact.bgr, cv::NORM_L1) / (3.0 * f.bgr.total());
  EXPECT_GT(mean_abs, 0.6);
  EXPECT_LT(mean_abs, 2.5);
}

// The errors of a flat wall at 1.5 m, in units of the modelled sigma there, without quantisation
// or rounding: what the noise itself is.
cv::Mat standardisedErrors(const KinectNoise& model, std::uint64_t seed) {
  const float z = 1.5f;
  const cv::Mat exact(480, 640, CV_32FC1, cv::Scalar(z));
  KinectNoise noise = model;
  noise.disparity_step = 0.0;
  const cv::Mat measured = degradeDepth(exact, noise, 0.0, seed);
  cv::Mat errors = (measured - z) / noise.depthSigma(z);
  return errors;
}

// The correlation of the errors of pixels d apart along rows and columns.
double correlationAt(const cv::Mat& e, int d) {
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (int v = 0; v + d < e.rows; ++v) {
    for (int u = 0; u + d < e.cols; ++u) {
      const double a = e.at<float>(v, u);
      for (const double b : {double(e.at<float>(v, u + d)), double(e.at<float>(v + d, u))}) {
        ab += a * b, aa += a * a, bb += b * b;
      }
    }
  }
  return ab / std::sqrt(aa * bb);
}

// A structured-light sensor errs in blobs (--depth-noise-correlation): the field keeps the
// modelled standard deviation and correlates pixels d apart by exp(-d^2 / (4 L^2)); per pixel
// (L = 0, the default) neighbours are independent. Deterministic for a seed.
TEST(SynthNoise, CorrelatedDepthNoiseComesInBlobsOfTheStatedLength) {
  KinectNoise independent;
  const cv::Mat e0 = standardisedErrors(independent, 5);
  cv::Scalar mean, sd;
  cv::meanStdDev(e0, mean, sd);
  EXPECT_NEAR(sd[0], 1.0, 0.02);
  EXPECT_NEAR(mean[0], 0.0, 0.01);
  EXPECT_NEAR(correlationAt(e0, 1), 0.0, 0.01);

  KinectNoise blobs;
  blobs.correlation_px = 3.0;
  const cv::Mat e3 = standardisedErrors(blobs, 5);
  cv::meanStdDev(e3, mean, sd);
  // About 640 x 480 / (4 pi 3^2) independent blobs: the sample's spread is known to a few %.
  // Measured: 1.006, and 0.973, 0.896, 0.645, 0.175 at 1, 2, 4, 8 px.
  EXPECT_NEAR(sd[0], 1.0, 0.03);
  EXPECT_NEAR(mean[0], 0.0, 0.05);
  std::printf("  blobs of 3 px: std %.3f;", sd[0]);
  for (const int d : {1, 2, 4, 8}) {
    const double expected = std::exp(-d * d / (4.0 * 3.0 * 3.0));
    const double measured = correlationAt(e3, d);
    std::printf(" %d px %.3f (%.3f)", d, measured, expected);
    EXPECT_NEAR(measured, expected, 0.03) << d << " px apart";
  }
  std::printf("\n");
  EXPECT_LT(cv::norm(e3, standardisedErrors(blobs, 5), cv::NORM_INF), 1e-6);
  EXPECT_GT(cv::norm(e3, standardisedErrors(blobs, 6), cv::NORM_L1), 0.5 * e3.total());
}

// A sensor's fixed distortion (--depth-distortion): the depth of a flat wall, without noise,
// is scaled by 1 + R D(u, v), D smooth and of unit variance, the same in every frame (the frame's
// noise seed does not move it) and another sensor's with another distortion seed.
TEST(SynthNoise, FixedDepthDistortionStaysInTheImageFromFrameToFrame) {
  const float z = 1.5f;
  const cv::Mat exact(480, 640, CV_32FC1, cv::Scalar(z));
  KinectNoise sensor;
  sensor.sigma_base = sensor.sigma_quadratic = 0.0;
  sensor.disparity_step = 0.0;
  sensor.distortion_relative = 0.005;
  sensor.distortion_seed = 7;
  const auto relative = [&](const KinectNoise& n, std::uint64_t frame_seed) {
    const cv::Mat measured = degradeDepth(exact, n, 0.0, frame_seed);
    return cv::Mat((measured - z) / (z * n.distortion_relative));
  };
  const cv::Mat d = relative(sensor, 1);
  cv::Scalar mean, sd;
  cv::meanStdDev(d, mean, sd);
  EXPECT_NEAR(sd[0], 1.0, 1e-3);
  EXPECT_NEAR(mean[0], 0.0, 1e-3);
  // Smooth: pixels 10 apart err alike (measured 0.996), unlike per-pixel or 3 px blobs.
  const double near = correlationAt(d, 10);
  std::printf("  fixed distortion: correlation at 10 px %.3f, at 80 px %.3f\n", near,
              correlationAt(d, 80));
  EXPECT_GT(near, 0.98);
  EXPECT_LT(cv::norm(d, relative(sensor, 2), cv::NORM_INF), 1e-3);
  KinectNoise other = sensor;
  other.distortion_seed = 8;
  EXPECT_GT(cv::norm(d, relative(other, 1), cv::NORM_L1), 0.3 * double(d.total()));
}

TEST(SynthNoise, OutOfRangeDepthIsInvalid) {
  RenderOptions noisy;
  noisy.noise = true;
  noisy.kinect.max_depth = 3.0;
  const SynthFrame exact = render(makeScene({true, true, 1}), defaultStartPose(), exactOptions());
  const SynthFrame f = render(makeScene({true, true, 1}), defaultStartPose(), noisy, 1);
  double lo = 0, hi = 0;
  cv::minMaxLoc(f.depth_m, &lo, &hi);
  EXPECT_LE(hi, 3.0);
  EXPECT_EQ(cv::countNonZero((f.depth_m > 0) & (exact.depth_m > 3.3)), 0);
  EXPECT_GT(cv::countNonZero(exact.depth_m > 3.3), 10000);
}

TEST(SynthBlur, BlurSmoothsColourButNotDepth) {
  const Scene scene = makeScene({true, true, 1});
  MotionOptions m;
  m.speed = 1.0;
  const Motion motion(m);
  const Eigen::Isometry3d pose = motion.poseAt(1.0);
  std::vector<Eigen::Isometry3d> exposure;
  for (int k = 0; k < 5; ++k) exposure.push_back(motion.poseAt(1.0 + (k - 2) / 240.0));
  const SynthFrame sharp = render(scene, pose, exactOptions());
  const SynthFrame blurred = renderBlurred(scene, pose, exposure, exactOptions());
  EXPECT_EQ(cv::norm(sharp.depth_m, blurred.depth_m, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(sharp.bgr, blurred.bgr, cv::NORM_L1) / sharp.bgr.total(), 1.0);
  EXPECT_LT(cv::sum(gradientMagnitude(blurred.bgr))[0],
            0.9 * cv::sum(gradientMagnitude(sharp.bgr))[0]);
  // A still camera blurs nothing.
  const SynthFrame still = renderBlurred(scene, pose, {pose, pose, pose}, exactOptions());
  EXPECT_EQ(cv::norm(sharp.bgr, still.bgr, cv::NORM_INF), 0.0);
}

TEST(SynthSequence, KnownRelativeMotionReprojectsDepth) {
  SequenceOptions o;
  o.frames = 20;
  o.noise = false;
  o.seed = 9;
  const SynthSequence seq(o);
  const SynthFrame a = seq.frame(0), b = seq.frame(15);
  EXPECT_DOUBLE_EQ(b.stamp, 1000.0 + 15 / 30.0);
  EXPECT_EQ((b.pose.matrix() - seq.poses()[15].matrix()).norm(), 0.0);
  // Maps points of b's optical frame into a's.
  const Eigen::Isometry3d b_to_a = a.pose.inverse() * b.pose;
  ASSERT_GT(b_to_a.translation().norm(), 0.02);
  std::vector<double> errors;
  for (int v = 10; v < 470; v += 6) {
    for (int u = 10; u < 630; u += 6) {
      const Eigen::Vector3d p = b_to_a * b.camera.backProject(u, v, b.depth_m.at<float>(v, u));
      const Eigen::Vector2d px = a.camera.project(p);
      const int ua = static_cast<int>(std::lround(px.x())),
                va = static_cast<int>(std::lround(px.y()));
      if (ua < 1 || va < 1 || ua >= 639 || va >= 479) continue;
      if (a.surface.at<int>(va, ua) != b.surface.at<int>(v, u)) continue;  // occluded or edge
      errors.push_back(std::abs(p.z() - a.depth_m.at<float>(va, ua)));
    }
  }
  ASSERT_GT(errors.size(), 3000u);
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  // What remains is the depth change over the half pixel of rounding to the nearest pixel.
  EXPECT_LT(errors[errors.size() / 2], 0.005);
}

// A walker (SequenceOptions::walker_speed) is the one thing that moves: the room without it is
// the room of walker off, pixel for pixel, wherever the walker is not seen; where it is seen it
// stands in front of the room; and it walks at the speed asked, across the start's view.
TEST(SynthSequence, AWalkerMovesThroughAStillRoom) {
  SequenceOptions o;
  o.frames = 2;
  o.noise = false;
  o.seed = 61;
  o.motion = MotionKind::kStill;
  const SynthSequence room(o);
  o.walker_speed = 1.0;
  const SynthSequence walked(o);
  EXPECT_EQ(walked.scene().boxes.size(), room.scene().boxes.size());
  ASSERT_EQ(walked.scene().materials.size(), room.scene().materials.size() + 1);
  for (std::size_t m = 0; m < room.scene().materials.size(); ++m) {
    EXPECT_EQ(walked.scene().materials[m].base, room.scene().materials[m].base);
  }
  const int walker_first = walked.sceneAt(0.0).surfaceCount() - 6;  // its six faces
  EXPECT_EQ(walker_first, room.scene().surfaceCount());

  const SynthFrame still = room.frame(0);
  const Eigen::Isometry3d pose = room.poses()[0];
  const RenderOptions exact = o.renderOptions();
  int seen = 0, elsewhere_changed = 0;
  for (const double t : {0.0, 2.0}) {
    const SynthFrame f = render(walked.sceneAt(t), pose, exact);
    int walker_pixels = 0;
    for (int v = 0; v < f.depth_m.rows; ++v) {
      for (int u = 0; u < f.depth_m.cols; ++u) {
        if (f.surface.at<int>(v, u) >= walker_first) {
          ++walker_pixels;
          EXPECT_LT(f.depth_m.at<float>(v, u), still.depth_m.at<float>(v, u) + 1e-6f);
        } else if (f.depth_m.at<float>(v, u) != still.depth_m.at<float>(v, u) ||
                   f.bgr.at<cv::Vec3b>(v, u) != still.bgr.at<cv::Vec3b>(v, u)) {
          ++elsewhere_changed;
        }
      }
    }
    // In the middle of the start's view at t = 0 (measured: 37% of the image); 1.77 m to the
    // side two seconds later at 1 m/s, out of view.
    if (t == 0.0) {
      EXPECT_GT(walker_pixels, int(f.depth_m.total() * 3 / 10));
    } else {
      EXPECT_EQ(walker_pixels, 0);
    }
    seen += walker_pixels;
  }
  EXPECT_GT(seen, 0);
  EXPECT_EQ(elsewhere_changed, 0);

  // Its mean speed over a whole back-and-forth, from its positions 1 ms apart.
  const double period = 4 * 1.8 / o.walker_speed;
  double path = 0.0;
  Eigen::Vector3d last = walkerAt(o.walker_speed, 0.0, 0).box_to_world.translation();
  for (double t = 0.001; t <= period + 1e-9; t += 0.001) {
    const Eigen::Vector3d at = walkerAt(o.walker_speed, t, 0).box_to_world.translation();
    path += (at - last).norm();
    last = at;
  }
  EXPECT_NEAR(path / period, 1.0, 0.005);
  EXPECT_NEAR(last.x(), 0.0, 1e-2);  // back where it started
  EXPECT_EQ(last.z(), 0.85);         // standing on the floor

  o.structure = false;  // nothing to walk through
  EXPECT_THROW(SynthSequence{o}, std::invalid_argument);
  o.structure = true;
  o.walker_speed = -1.0;
  EXPECT_THROW(SynthSequence{o}, std::invalid_argument);
}

TEST(SynthSequence, ScaledCameraKeepsTheFieldOfView) {
  const Camera full = scaledDefaultCamera(640, 480);
  EXPECT_EQ(full.fx, 525.0);
  EXPECT_EQ(full.cx, 319.5);
  EXPECT_EQ(full.cy, 239.5);
  const Camera small = scaledDefaultCamera(160, 120);
  EXPECT_DOUBLE_EQ(small.fx, 131.25);
  EXPECT_DOUBLE_EQ(small.fy, 131.25);
  EXPECT_DOUBLE_EQ(small.cx, 79.5);
  EXPECT_DOUBLE_EQ(small.cy, 59.5);
  EXPECT_EQ(small.width, 160);
  EXPECT_EQ(small.height, 120);
}

}  // namespace
}  // namespace acvo::synth
