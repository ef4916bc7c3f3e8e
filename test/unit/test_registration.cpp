// Whole registrations on rendered image pairs with exactly known motion (noise-free).
#include <algorithm>
#include <ostream>
#include <vector>

#include <gtest/gtest.h>

#include "acvo/labelled_cloud.hpp"
#include "acvo/registration.hpp"
#include "acvo/registration/paper.hpp"
#include "acvo/se3.hpp"
#include "synth/layout.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "synth/sequence.hpp"

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

// Each engine as the odometry runs it: coarse_to_fine with its own defaults, the paper's A-CVO
// and CVO with the authors' settings.
struct Setting {
  const char* name;
  Params params;
};

void PrintTo(const Setting& s, std::ostream* os) {
  *os << s.name;
}

Params withIterations(Params p, int n) {
  p.paper.max_iterations = n;
  return p;
}

// CVO's schedule with A-CVO's colour length-scale (0.5). With the authors' CVO value (1.5 here:
// colour all but ignored) the pure 5 deg yaw of this room ends 2.6 deg off: geometry alone
// holds a local optimum there, which is the authors' CVO, not a fault of the schedule.
Params cvoWithColour() {
  Params p = withIterations(cvoParams(), 400);
  p.paper.color_ell = 0.5;
  return p;
}

class Registration : public ::testing::TestWithParam<Setting> {};

TEST_P(Registration, RecoversKnownMotionsOfARenderedRoom) {
  const synth::Scene scene = synth::makeScene({true, true, 3});
  synth::RenderOptions ro;  // TUM default camera, noise off
  const Eigen::Isometry3d pose_a = synth::defaultStartPose();
  const Params& params = GetParam().params;
  const auto engine = makeRegistrationEngine(params);
  const Frame fa = synth::render(scene, pose_a, ro).toFrame();
  const auto A = engine->prepare(buildLabelledCloud(fa, params.selection), true);
  for (const Motion& m : kMotions) {
    const Eigen::Isometry3d b_to_a = expSE3(m.twist);
    const Frame fb = synth::render(scene, pose_a * b_to_a, ro).toFrame();
    const auto B = engine->prepare(buildLabelledCloud(fb, params.selection), false);
    // Each pair as the first registration of a sequence: CVO's engine carries its length-scale
    // from one registration to the next (paper.carry_ell), which is not what is tested here.
    const SolverResult r =
        makeRegistrationEngine(params)->align(*A, *B, Eigen::Isometry3d::Identity());
    const Vector6d err = logSE3(b_to_a.inverse() * r.transform);
    const double err_mm = 1000.0 * err.tail<3>().norm(), err_deg = err.head<3>().norm() * 180 / M_PI;
    std::printf("  %-26s %s: %3d iterations, error %.3f mm %.4f deg\n", m.name, GetParam().name,
                r.iterations, err_mm, err_deg);
    EXPECT_NE(r.status, SolverStatus::kNotFinite);
    EXPECT_LT(err_mm, 1.0) << m.name;
    EXPECT_LT(err_deg, 0.1) << m.name;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryEngine, Registration,
                         ::testing::Values(Setting{"coarse_to_fine", Params()},
                                           Setting{"acvo", withIterations(paperParams(), 400)},
                                           Setting{"cvo", cvoWithColour()}),
                         [](const auto& info) { return std::string(info.param.name); });

// The stall rule (PaperParams::stall_iterations, not in the paper) on the case it was made for: a room of flat
// colours seen by a noisy sensor, where the adaptive length-scale often settles at ell_min and
// the iterates then circle the optimum without improving the objective. Consecutive frames of
// a synthetic sequence, each registration started from the true previous motion.
TEST(StallRule, CutsIterationsOnAnUntexturedRoomWithoutLosingAccuracy) {
  synth::SequenceOptions o;
  o.frames = 41;
  o.texture = false;
  const synth::SynthSequence seq(o);
  // The settings the rule was measured with: the paper's engine with this package's speed-ups.
  Params params = paperParams();
  PaperParams& p = params.paper;
  p.direction = SearchDirection::kConjugateGradient;
  p.ell_update = EllUpdate::kDescent;
  p.color_ell = 0.1;
  p.coarse_ell = 0.4;
  p.max_iterations = 200;
  const int stall_default = 6;
  std::vector<std::shared_ptr<PaperCloud>> clouds;
  for (int i = 0; i < seq.size(); ++i)
    clouds.push_back(
        preparePaper(buildLabelledCloud(seq.frame(i).toFrame(), params.selection), p, true));
  int iterations[2] = {0, 0}, stalled = 0;
  double sum_mm[2] = {0, 0}, sum_deg[2] = {0, 0};
  for (int i = 1; i + 1 < seq.size(); ++i) {
    const Eigen::Isometry3d truth = seq.poses()[i].inverse() * seq.poses()[i + 1];
    const Eigen::Isometry3d guess = seq.poses()[i - 1].inverse() * seq.poses()[i];
    for (int on : {0, 1}) {
      p.stall_iterations = on ? stall_default : 0;
      const SolverResult r = alignPaper(*clouds[i], *clouds[i + 1], guess, p);
      ASSERT_NE(r.status, SolverStatus::kNotFinite);
      const Vector6d err = logSE3(truth.inverse() * r.transform);
      iterations[on] += r.iterations;
      sum_mm[on] += 1000.0 * err.tail<3>().norm();
      sum_deg[on] += err.head<3>().norm() * 180 / M_PI;
      // The returned transform is the best seen at the final length-scale.
      EXPECT_TRUE(on || !r.stalled);
      if (r.stalled) {
        ++stalled;
        EXPECT_EQ(r.status, SolverStatus::kConverged);
        double best = -1.0;
        for (const IterationTrace& t : r.trace)
          if (t.ell == r.ell) best = std::max(best, t.objective);
        EXPECT_GE(r.objective, best - 1e-12) << "frame " << i;
      }
    }
  }
  const int pairs = seq.size() - 2;
  std::printf("  stall off: %d iterations, mean error %.3f mm %.4f deg\n", iterations[0],
              sum_mm[0] / pairs, sum_deg[0] / pairs);
  std::printf("  stall on:  %d iterations, mean error %.3f mm %.4f deg (%d stopped by the rule)\n",
              iterations[1], sum_mm[1] / pairs, sum_deg[1] / pairs, stalled);
  // Measured: 1887 -> 1755 iterations, 2.47 -> 2.10 mm, 0.061 -> 0.054 deg, 7 of 39 stopped.
  EXPECT_GE(stalled, 3);
  EXPECT_LT(iterations[1], iterations[0]);
  EXPECT_LT(sum_mm[1], 1.1 * sum_mm[0]);
  EXPECT_LT(sum_deg[1], 1.1 * sum_deg[0]);
}

}  // namespace
}  // namespace acvo
