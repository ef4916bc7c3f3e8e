// Whole registrations on rendered image pairs with exactly known motion (noise-free).
#include <gtest/gtest.h>

#include "acvo/kernel.hpp"
#include "acvo/labelled_cloud.hpp"
#include "acvo/se3.hpp"
#include "acvo/solver.hpp"
#include "synth/layout.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"

namespace acvo {
namespace {

struct Motion {
  const char* name;
  Vector6d twist;  // (rotation, translation) of camera b in camera a's frame
};

Vector6d twist(double rx_deg, double ry_deg, double rz_deg, double tx, double ty, double tz) {
  const double k = M_PI / 180.0;
  return (Vector6d() << rx_deg * k, ry_deg * k, rz_deg * k, tx, ty, tz).finished();
}

const Motion kMotions[] = {
    {"translation x 5 cm", twist(0, 0, 0, 0.05, 0, 0)},
    {"translation 5 cm oblique", twist(0, 0, 0, 0.025, -0.03, 0.03)},
    {"rotation yaw 5 deg", twist(0, 5, 0, 0, 0, 0)},
    {"rotation 5 deg oblique", twist(3, -2.5, 3, 0, 0, 0)},
    {"both 3 deg 3 cm", twist(1.5, 2, -1.5, -0.02, 0.01, 0.02)},
};

class Registration : public ::testing::TestWithParam<EllPolicy> {};

TEST_P(Registration, RecoversKnownMotionsOfARenderedRoom) {
  const synth::Scene scene = synth::makeScene({true, true, 3});
  synth::RenderOptions ro;  // TUM default camera, noise off
  const Eigen::Isometry3d pose_a = synth::defaultStartPose();
  Params params;
  params.solver.ell_policy = GetParam();
  params.solver.max_iterations = 400;
  const Frame fa = synth::render(scene, pose_a, ro).toFrame();
  const PreparedCloud A = prepareCloud(buildLabelledCloud(fa, params.selection), params.solver);
  for (const Motion& m : kMotions) {
    const Eigen::Isometry3d b_to_a = expSE3(m.twist);
    const Frame fb = synth::render(scene, pose_a * b_to_a, ro).toFrame();
    const PreparedCloud B = prepareCloud(buildLabelledCloud(fb, params.selection), params.solver);
    const SolverResult r = align(A, B, Eigen::Isometry3d::Identity(), params.solver);
    const Vector6d err = logSE3(b_to_a.inverse() * r.transform);
    const double err_mm = 1000.0 * err.tail<3>().norm(), err_deg = err.head<3>().norm() * 180 / M_PI;
    std::printf("  %-26s %s: %3d iterations, error %.3f mm %.4f deg\n", m.name,
                toString(GetParam()).c_str(), r.iterations, err_mm, err_deg);
    EXPECT_NE(r.status, SolverStatus::kNotFinite);
    EXPECT_LT(err_mm, 1.0) << m.name;
    EXPECT_LT(err_deg, 0.1) << m.name;
  }
}

INSTANTIATE_TEST_SUITE_P(BothPolicies, Registration,
                         ::testing::Values(EllPolicy::kAdaptive, EllPolicy::kFixedSchedule),
                         [](const auto& info) { return toString(info.param); });

}  // namespace
}  // namespace acvo
