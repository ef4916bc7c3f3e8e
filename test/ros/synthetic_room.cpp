#include "synthetic_room.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "synth/layout.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "synth/sequence.hpp"

namespace acvo_test {
namespace {

const acvo::synth::Scene& scene() {
  static const acvo::synth::Scene s = acvo::synth::makeScene(acvo::synth::SceneOptions{});
  return s;
}

}  // namespace

acvo::Camera testCamera() {
  acvo::Camera c = acvo::synth::scaledDefaultCamera(320, 240);
  c.depth_scale = 1.0;
  return c;
}

RgbdImage renderRoom(const Eigen::Isometry3d& world_from_camera, const acvo::Camera& camera,
                     double colour_focal_ratio) {
  acvo::synth::RenderOptions options;
  options.camera = camera;
  options.noise = false;
  options.colour_focal_ratio = colour_focal_ratio;
  const acvo::synth::SynthFrame f = acvo::synth::render(scene(), world_from_camera, options);
  RgbdImage out;
  cv::cvtColor(f.bgr, out.rgb, cv::COLOR_BGR2RGB);
  out.depth = f.depth_m.clone();
  return out;
}

Eigen::Isometry3d frameMotion() {
  const Eigen::Vector3d omega = Eigen::Vector3d(0.2, 0.6, 0.1) * (M_PI / 180.0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(omega.norm(), omega.normalized()).matrix();
  t.translation() << 0.010, -0.004, 0.011;
  return t;
}

Eigen::Isometry3d cameraPose(int k) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int i = 0; i < k; ++i) pose = pose * frameMotion();
  return pose;
}

Eigen::Isometry3d worldFromFirstCamera() {
  return acvo::synth::defaultStartPose();
}

}  // namespace acvo_test
