// The local window's cost, gradient and refinement (odometry/window.hpp), its work on a thread of
// its own (odometry/keyframe_window.hpp) and the odometry with it (docs/method.md §7.7).
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "acvo/cloud/labelled_cloud.hpp"
#include "acvo/odometry/keyframe_window.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/odometry/window.hpp"
#include "se3_fixtures.hpp"
#include "synth/sequence.hpp"

namespace acvo {
namespace {

using test::randomTwist;

// A positive definite information with rotation-translation coupling, as a registration's.
Matrix6d randomInformation(std::mt19937& rng) {
  Matrix6d a;
  std::normal_distribution<double> n(0.0, 1.0);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) a(r, c) = n(rng);
  }
  return a * a.transpose() + 6.0 * Matrix6d::Identity();
}

// Four keyframes moving along a hand-held path; every pair linked, each link's measurement the
// true relative motion times an error.
struct Window {
  std::vector<Eigen::Isometry3d> truth, poses;
  std::vector<WindowLink> links;
};

Window makeWindow(std::mt19937& rng, double measurement_error, double pose_error) {
  Window w;
  Eigen::Isometry3d pose = expSE3(randomTwist(rng, 0.5, 1.0));
  for (int k = 0; k < 4; ++k) {
    w.truth.push_back(pose);
    pose = pose * expSE3(randomTwist(rng, 0.05, 0.05));
  }
  for (int m = 1; m < 4; ++m) {
    for (int f = 0; f < m; ++f) {
      const Eigen::Isometry3d relative =
          w.truth[std::size_t(f)].inverse() * w.truth[std::size_t(m)];
      w.links.push_back({f, m,
                         expSE3(randomTwist(rng, measurement_error, measurement_error)) * relative,
                         randomInformation(rng)});
    }
  }
  for (const Eigen::Isometry3d& t : w.truth) {
    w.poses.push_back(expSE3(randomTwist(rng, pose_error, pose_error)) * t);
  }
  w.poses[0] = w.truth[0];
  return w;
}

TEST(Window, GradientMatchesFiniteDifferencesOfTheCost) {
  // Far from the optimum (links 0.05 rad / m off, poses 0.1 off), where the left Jacobian's
  // inverse is not the identity.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    Window w = makeWindow(rng, 0.05, 0.1);
    const Eigen::VectorXd g = windowGradient(w.poses, w.links);
    const double h = 1e-6;
    for (std::size_t p = 0; p < w.poses.size(); ++p) {
      for (int k = 0; k < 6; ++k) {
        std::vector<Eigen::Isometry3d> plus = w.poses, minus = w.poses;
        plus[p] = expSE3(Vector6d::Unit(k) * h) * w.poses[p];
        minus[p] = expSE3(-Vector6d::Unit(k) * h) * w.poses[p];
        const double numeric = (windowCost(plus, w.links) - windowCost(minus, w.links)) / (2.0 * h);
        EXPECT_NEAR(g[Eigen::Index(6 * p) + k], numeric, 1e-6 * (1.0 + std::abs(numeric)))
            << "pose " << p << " coordinate " << k;
      }
    }
  }
}

TEST(Window, RefinementReachesTheMinimumAndHoldsTheFirstPose) {
  std::mt19937 rng(5);
  Window w = makeWindow(rng, 0.01, 0.05);
  const Eigen::Isometry3d first = w.poses[0];
  const double before = windowCost(w.poses, w.links);
  const int iterations = refineWindow(w.poses, w.links);
  EXPECT_GT(iterations, 1);
  EXPECT_LT(iterations, 10);
  EXPECT_LT(windowCost(w.poses, w.links), 0.5 * before);
  // A minimum: the gradient of every free pose vanishes, and no small move of one lowers the
  // cost.
  const Eigen::VectorXd g = windowGradient(w.poses, w.links);
  EXPECT_LT(g.tail(g.size() - 6).norm(), 1e-9);
  const double at_minimum = windowCost(w.poses, w.links);
  for (std::size_t p = 1; p < w.poses.size(); ++p) {
    for (int k = 0; k < 6; ++k) {
      std::vector<Eigen::Isometry3d> moved = w.poses;
      moved[p] = expSE3(Vector6d::Unit(k) * 1e-4) * w.poses[p];
      EXPECT_GT(windowCost(moved, w.links), at_minimum);
    }
  }
  EXPECT_TRUE(w.poses[0].isApprox(first, 0.0));
}

TEST(Window, ConsistentLinksGiveTheTruePosesExactly) {
  std::mt19937 rng(9);
  Window w = makeWindow(rng, 0.0, 0.1);
  refineWindow(w.poses, w.links);
  for (std::size_t k = 0; k < w.poses.size(); ++k) {
    EXPECT_LT(logSE3(w.truth[k].inverse() * w.poses[k]).norm(), 1e-10) << "pose " << k;
  }
}

TEST(Window, TheBetterLinkWeighsMore) {
  // Two keyframes linked to the fixed one: directly (b), and through a (a then b). A direct link
  // ten times more informative than the chain pulls b ten times closer to itself.
  std::vector<Eigen::Isometry3d> poses(3, Eigen::Isometry3d::Identity());
  const Eigen::Isometry3d step(Eigen::Translation3d(0.1, 0.0, 0.0));
  const Eigen::Isometry3d direct(Eigen::Translation3d(0.2 + 0.011, 0.0, 0.0));
  const Matrix6d info = Matrix6d::Identity();
  const std::vector<WindowLink> links{
      {0, 1, step, 2.0 * info}, {1, 2, step, 2.0 * info}, {0, 2, direct, 10.0 * info}};
  poses[1] = step;
  poses[2] = step * step;
  refineWindow(poses, links);
  // Chain information 1 (two links of 2 in series), direct 10: b at 0.2 + 0.011 * 10/11.
  EXPECT_NEAR(poses[2].translation().x(), 0.2 + 0.011 * 10.0 / 11.0, 1e-9);
  EXPECT_NEAR(poses[1].translation().x(), 0.1 + 0.011 * 10.0 / 11.0 / 2.0, 1e-9);
}

TEST(Window, HeldPosesStayAndAnUnlinkedPoseKeepsItsValue) {
  std::mt19937 rng(11);
  Window w = makeWindow(rng, 0.01, 0.05);
  const std::vector<Eigen::Isometry3d> before = w.poses;
  // Only the links of pose 3 to the two held poses: pose 2 is reached by none.
  std::vector<WindowLink> links;
  for (const WindowLink& l : w.links) {
    if (l.moving == 3 && l.fixed < 2) links.push_back(l);
  }
  refineWindow(w.poses, links, 2);
  EXPECT_TRUE(w.poses[0].isApprox(before[0], 0.0));
  EXPECT_TRUE(w.poses[1].isApprox(before[1], 0.0));
  EXPECT_TRUE(w.poses[2].isApprox(before[2], 1e-12));
  EXPECT_FALSE(w.poses[3].isApprox(before[3], 1e-6));
  EXPECT_LT(windowGradient(w.poses, links).tail<6>().norm(), 1e-8);
}

TEST(Window, ACentreLinkIsAFullLinkWhoseRotationIsUnknown) {
  // centreInformation is the limit of the full information as the rotation's variance about the
  // moving keyframe's centre grows without bound: the rotation is left free, not held known.
  std::mt19937 rng(13);
  for (int trial = 0; trial < 5; ++trial) {
    const Matrix6d covariance = randomInformation(rng).inverse();
    const Eigen::Isometry3d measured = expSE3(randomTwist(rng, 0.3, 0.5));
    const std::optional<Matrix6d> centre = centreInformation(covariance, measured);
    ASSERT_TRUE(centre.has_value());
    // A rotation variance k (1e7) about the centre is Ad(T_hat) diag(k, 0) Ad(T_hat)^T in
    // the left perturbation's coordinates.
    const Matrix6d to_left = adjointSE3(measured);
    Matrix6d free_rotation = Matrix6d::Zero();
    free_rotation.topLeftCorner<3, 3>() = 1e7 * Eigen::Matrix3d::Identity();
    const Matrix6d limit = (covariance + to_left * free_rotation * to_left.transpose()).inverse();
    EXPECT_LT((limit - *centre).norm(), 1e-5 * centre->norm()) << "trial " << trial;
    // Not the translation block of the full information in the right perturbation's coordinates
    // (that would hold the rotation known).
    const Matrix6d to_right = to_left.inverse();
    Matrix6d held = Matrix6d::Zero();
    held.bottomRightCorner<3, 3>() =
        (to_left.transpose() * covariance.inverse() * to_left).bottomRightCorner<3, 3>();
    EXPECT_GT((to_right.transpose() * held * to_right - *centre).norm(), 0.1 * centre->norm());
  }
  EXPECT_FALSE(centreInformation(Matrix6d::Zero(), Eigen::Isometry3d::Identity()).has_value());
}

TEST(Window, ALinkThatDisagreesOnlyInRotationMovesNoPose) {
  // Three keyframes along a path, chained by exact links. A link from the first to the third
  // whose transform is turned about the third's centre moves nothing as a centre link, and pulls
  // the third's rotation as a full one.
  std::mt19937 rng(17);
  std::vector<Eigen::Isometry3d> truth{expSE3(randomTwist(rng, 0.5, 1.0))};
  for (int k = 0; k < 2; ++k) truth.push_back(truth.back() * expSE3(randomTwist(rng, 0.1, 0.2)));
  const Matrix6d info = randomInformation(rng);
  const Eigen::Isometry3d turned = truth[0].inverse() * truth[2] *
                                   expSE3((Vector6d() << 0.02, -0.01, 0.015, 0, 0, 0).finished());
  const Matrix6d covariance = randomInformation(rng).inverse();
  const std::optional<Matrix6d> centre = centreInformation(covariance, turned);
  ASSERT_TRUE(centre.has_value());
  for (const bool centre_only : {true, false}) {
    std::vector<Eigen::Isometry3d> poses = truth;
    const Matrix6d long_info = centre_only ? *centre : Matrix6d(covariance.inverse());
    const std::vector<WindowLink> links{{0, 1, truth[0].inverse() * truth[1], info},
                                        {1, 2, truth[1].inverse() * truth[2], info},
                                        {0, 2, turned, long_info}};
    refineWindow(poses, links);
    const double moved = logSE3(truth[2].inverse() * poses[2]).norm();
    if (centre_only) {
      EXPECT_LT(moved, 1e-10);
      EXPECT_LT(logSE3(truth[1].inverse() * poses[1]).norm(), 1e-10);
    } else {
      EXPECT_GT(moved, 1e-3);
    }
  }
}

// An engine that registers as the built-in one does, says whether it is reentrant as told, and
// records the threads its registrations ran on.
class RecordingEngine : public RegistrationEngine {
 public:
  RecordingEngine(std::shared_ptr<const RegistrationEngine> engine, bool reentrant)
      : engine_(std::move(engine)), reentrant_(reentrant) {}
  std::shared_ptr<PreparedCloud> prepare(LabelledCloud cloud, bool as_reference) const override {
    return engine_->prepare(std::move(cloud), as_reference);
  }
  double prepareReference(PreparedCloud& cloud) const override {
    return engine_->prepareReference(cloud);
  }
  using RegistrationEngine::align;
  SolverResult align(const PreparedCloud& fixed, const PreparedCloud& moving,
                     const Eigen::Isometry3d& guess, AlignStages stages) const override {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      threads_.insert(std::this_thread::get_id());
    }
    return engine_->align(fixed, moving, guess, stages);
  }
  bool staged() const override { return engine_->staged(); }
  bool reentrant() const override { return reentrant_; }
  std::optional<Matrix6d> covariance(const SolverResult& s,
                                     std::size_t moving_points) const override {
    return engine_->covariance(s, moving_points);
  }
  int minPoints() const override { return engine_->minPoints(); }
  std::set<std::thread::id> threads() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return threads_;
  }

 private:
  std::shared_ptr<const RegistrationEngine> engine_;
  bool reentrant_;
  mutable std::mutex mutex_;
  mutable std::set<std::thread::id> threads_;
};

// Every third frame of a rendered hand-held camera entered as a keyframe, registered to the one
// before from the true motion; the window's updates, each taken after the next enter()'s caller
// would have registered a frame.
std::vector<WindowUpdate> enterKeyframes(const synth::SynthSequence& seq, const Params& p,
                                         const std::shared_ptr<const RegistrationEngine>& engine) {
  KeyframeWindow window(4, p.odometry, 1);
  std::vector<WindowUpdate> updates;
  WindowKeyframe keyframe;
  for (int i = 0; i < seq.size(); i += 3) {
    WindowKeyframe frame;
    frame.cloud = engine->prepare(buildLabelledCloud(seq.frame(i).toFrame(), p.selection), true);
    frame.index = std::uint64_t(i);
    if (!keyframe.cloud) {
      frame.pose = seq.poses()[0];
      keyframe = frame;
      continue;
    }
    const Eigen::Isometry3d truth = seq.poses()[std::size_t(keyframe.index)].inverse() *
                                    seq.poses()[std::size_t(i)];
    const SolverResult s = engine->align(*keyframe.cloud, *frame.cloud, truth);
    const std::optional<Matrix6d> covariance = engine->covariance(s, frame.cloud->size());
    EXPECT_TRUE(covariance.has_value()) << "frame " << i;
    if (!covariance) break;
    frame.pose = keyframe.pose * s.transform;
    window.enter(engine, keyframe, frame, s.transform, *covariance);
    const std::optional<WindowUpdate> update = window.take();
    EXPECT_TRUE(update.has_value()) << "frame " << i;
    if (!update) break;
    EXPECT_EQ(update->index, frame.index);
    EXPECT_FALSE(window.take().has_value()) << "an update is taken once";
    updates.push_back(*update);
    keyframe = frame;
    keyframe.pose = update->pose;
  }
  window.clear();
  EXPECT_FALSE(window.take().has_value());
  return updates;
}

TEST(KeyframeWindow, ItsWorkRunsOnItsOwnThreadWhereTheEngineAllowsAndGivesTheSamePoses) {
  synth::SequenceOptions o;
  o.frames = 22;
  o.speed = 0.6;
  const synth::SynthSequence seq(o);
  Params p;
  const std::shared_ptr<const RegistrationEngine> built_in = makeRegistrationEngine(p);
  const auto alongside = std::make_shared<RecordingEngine>(built_in, true);
  const auto in_take = std::make_shared<RecordingEngine>(built_in, false);
  const std::vector<WindowUpdate> a = enterKeyframes(seq, p, alongside);
  const std::vector<WindowUpdate> b = enterKeyframes(seq, p, in_take);
  // A reentrant engine's registrations ran on the window's thread (besides the caller's own
  // registrations of the keyframes to each other); the other's on the caller's alone.
  const std::thread::id caller = std::this_thread::get_id();
  EXPECT_EQ(alongside->threads().size(), 2U);
  EXPECT_EQ(in_take->threads(), std::set<std::thread::id>{caller});
  // The same work either way: the same links and the same refined poses, to the last bit.
  ASSERT_EQ(a.size(), 7U);
  ASSERT_EQ(b.size(), a.size());
  int multi_linked = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].links, b[k].links) << "keyframe " << k;
    EXPECT_TRUE(a[k].pose.isApprox(b[k].pose, 0.0)) << "keyframe " << k;
    multi_linked += a[k].links > 1;
  }
  // The window refined them: keyframes linked to older ones than the one before, and moved.
  EXPECT_GE(multi_linked, 4);
  EXPECT_GT(a.back().shift, 0.0);
}

// The odometry with its window: a rendered hand-held camera (0.6 m/s, Kinect-like noise), so
// that keyframes come every few frames and link to the older ones in the window.
struct WindowRun {
  std::vector<Eigen::Isometry3d> published;
  int refined = 0;       // keyframes the window moved from their registration to the last
  int multi_linked = 0;  // keyframes linked to more than one older keyframe
};

WindowRun runWindow(const synth::SynthSequence& seq, int frames, const Params& p) {
  Odometry odo(p);
  odo.reset(seq.poses()[0]);
  WindowRun run;
  for (int i = 0; i < frames; ++i) {
    const OdometryResult r = odo.process(seq.frame(i).toFrame());
    EXPECT_NE(r.tracking, Tracking::kLost) << "frame " << i;
    // What the odometry holds as its pose is what it published.
    EXPECT_TRUE(odo.pose().isApprox(r.pose, 0.0)) << "frame " << i;
    run.published.push_back(r.pose);
    run.refined += r.window_shift > 0.0;
    run.multi_linked += r.window_links > 1;
  }
  return run;
}

TEST(WindowOdometry, APublishedPoseNeverChangesWithLaterFrames) {
  synth::SequenceOptions o;
  o.frames = 36;
  o.speed = 0.6;
  const synth::SynthSequence seq(o);
  Params p;
  p.odometry.window_keyframes = 4;
  p.odometry.threads = 1;
  const WindowRun whole = runWindow(seq, o.frames, p);
  EXPECT_GE(whole.multi_linked, 3);
  EXPECT_GE(whole.refined, 3);
  // The sequence cut short after frame k gives frame k the pose the whole run published for it:
  // no published pose depends on a later frame.
  for (const int k : {9, 20, 35}) {
    const WindowRun cut = runWindow(seq, k + 1, p);
    EXPECT_TRUE(cut.published.back().isApprox(whole.published[std::size_t(k)], 0.0))
        << "frame " << k;
  }
  // The window changes the trajectory: without it, the poses after the first refined keyframe
  // differ.
  p.odometry.window_keyframes = 2;
  const WindowRun alone = runWindow(seq, o.frames, p);
  EXPECT_EQ(alone.refined, 0);
  EXPECT_EQ(alone.multi_linked, 0);
  EXPECT_FALSE(alone.published.back().isApprox(whole.published.back(), 1e-9));
}

}  // namespace
}  // namespace acvo
