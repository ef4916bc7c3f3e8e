// The odometry's local window of keyframes (keyframe_window.hpp, docs/method.md §7.7), and the
// odometry's side of it (Odometry::newKeyframe, takeWindow).
#include "acvo/odometry/keyframe_window.hpp"

#include <algorithm>
#include <unordered_map>

#include <tbb/task_arena.h>

#include "acvo/odometry/covariance.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/odometry/tracking.hpp"
#include "acvo/timing.hpp"

namespace acvo {

int solverThreads(int setting) {
  if (setting > 0) return setting;
  if (setting == 0) return int(tbb::task_arena::automatic);
  return std::max(1, tbb::this_task_arena::max_concurrency() - 1);
}

struct KeyframeWindow::Arena {
  explicit Arena(int threads) : arena(solverThreads(threads)) {}
  tbb::task_arena arena;
};

KeyframeWindow::KeyframeWindow(std::size_t size, const OdometryParams& params, int threads)
    : size_(size), params_(params), arena_(std::make_unique<Arena>(threads)) {}

KeyframeWindow::~KeyframeWindow() {
  if (pending_.valid()) pending_.wait();
}

void KeyframeWindow::enter(std::shared_ptr<const RegistrationEngine> engine,
                           const WindowKeyframe& keyframe, const WindowKeyframe& frame,
                           const Eigen::Isometry3d& to_keyframe, const Matrix6d& covariance) {
  if (pending_.valid()) pending_.wait();
  pending_ = {};
  // The window holds the keyframes linked to one another since the last start or loss.
  if (keyframes_.empty() || keyframes_.back().index != keyframe.index) {
    keyframes_.assign(1, keyframe);
    links_.clear();
    anchors_.clear();
  }
  const std::optional<Matrix6d> information = scaledInverseInformation(covariance, 1.0);
  if (!information) {  // not constrained in every direction: the window starts again
    keyframes_.clear();
    return;
  }
  links_.push_back({keyframe.index, frame.index, to_keyframe, *information});
  // The work runs alongside the caller's next registration where the engine keeps no state
  // between registrations; otherwise when its update is taken.
  const auto policy = engine->reentrant() ? std::launch::async : std::launch::deferred;
  pending_ = std::async(policy, [this, engine = std::move(engine), frame] {
    WindowUpdate update;
    arena_->arena.execute([&] { update = work(*engine, frame); });
    return update;
  });
}

std::optional<WindowUpdate> KeyframeWindow::take() {
  if (!pending_.valid()) return std::nullopt;
  return pending_.get();
}

void KeyframeWindow::clear() {
  if (pending_.valid()) pending_.wait();
  pending_ = {};
  keyframes_.clear();
  links_.clear();
  anchors_.clear();
}

WindowUpdate KeyframeWindow::work(const RegistrationEngine& engine, WindowKeyframe frame) {
  WindowUpdate update;
  update.index = frame.index;
  update.links = 1;  // to the keyframe before, linked in enter()
  linkToOlderKeyframes(engine, frame, update);
  keyframes_.push_back(std::move(frame));
  leave();
  update.pose = refine();
  const Eigen::Isometry3d shift = keyframes_.back().pose.inverse() * update.pose;
  keyframes_.back().pose = update.pose;
  update.shift = shift.translation().norm();
  update.shift_deg = rotationDeg(shift);
  return update;
}

void KeyframeWindow::linkToOlderKeyframes(const RegistrationEngine& engine,
                                          const WindowKeyframe& frame, WindowUpdate& update) {
  // The keyframe before (the newest) is linked already.
  for (auto older = keyframes_.rbegin() + 1; older != keyframes_.rend(); ++older) {
    // From where the poses put it, a few millimetres off: the finest level alone, whose narrow
    // kernel holds the still part of the view where the coarse levels' wide one could follow a
    // person moving in it (as a second start does, second_start.hpp).
    const Eigen::Isometry3d guess = older->pose.inverse() * frame.pose;
    const SolverResult s = engine.align(*older->cloud, *frame.cloud, guess, AlignStages::kFinest);
    update.ms_registration += s.ms_total;
    // The registration must be one a frame would be tracked by, and move the pose no more than
    // a frame may move.
    const Judgement judgement = judgeTracking(s, guess.inverse() * s.transform, params_);
    if (judgement.tracking != Tracking::kOk) continue;
    // It says where the keyframe's centre lies, not how it is turned: on a real camera a
    // registration across several keyframes errs in rotation with its span, more than the chain
    // of shorter ones does (its depth's distortion is fixed in the image).
    const std::optional<Matrix6d> covariance = engine.covariance(s, frame.cloud->size());
    const std::optional<Matrix6d> information =
        covariance ? centreInformation(*covariance, s.transform) : std::nullopt;
    if (!information) continue;
    links_.push_back({older->index, frame.index, s.transform, *information});
    ++update.links;
  }
}

void KeyframeWindow::leave() {
  // The oldest keyframes leave with the poses they have: each keeps holding the keyframes it is
  // linked to, as long as they are in the window.
  while (keyframes_.size() > size_) {
    anchors_.emplace_back(keyframes_.front().index, keyframes_.front().pose);
    keyframes_.pop_front();
  }
  const auto in_window = [this](std::uint64_t index) {
    return std::any_of(keyframes_.begin(), keyframes_.end(),
                       [index](const WindowKeyframe& k) { return k.index == index; });
  };
  links_.erase(std::remove_if(links_.begin(), links_.end(),
                              [&](const Link& l) { return !in_window(l.moving); }),
               links_.end());
  const auto linked = [this](std::uint64_t index) {
    return std::any_of(links_.begin(), links_.end(),
                       [index](const Link& l) { return l.fixed == index; });
  };
  anchors_.erase(std::remove_if(anchors_.begin(), anchors_.end(),
                                [&](const auto& a) { return !linked(a.first); }),
                 anchors_.end());
}

Eigen::Isometry3d KeyframeWindow::refine() {
  // The keyframes that left the window first, held; without them, the oldest in it.
  std::unordered_map<std::uint64_t, int> position;
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& [index, pose] : anchors_) {
    position[index] = int(poses.size());
    poses.push_back(pose);
  }
  for (const WindowKeyframe& k : keyframes_) {
    position[k.index] = int(poses.size());
    poses.push_back(k.pose);
  }
  std::vector<WindowLink> links;
  for (const Link& l : links_) {
    links.push_back({position.at(l.fixed), position.at(l.moving), l.measured, l.information});
  }
  const int held = anchors_.empty() ? 1 : int(anchors_.size());
  refineWindow(poses, links, held);
  // Every keyframe but the newest keeps its refined pose here; the newest's is the update's.
  for (std::size_t k = 0; k + 1 < keyframes_.size(); ++k) {
    keyframes_[k].pose = poses[anchors_.size() + k];
  }
  return poses.back();
}

// The odometry's side of it.

void Odometry::newKeyframe(OdometryResult& r, Tracked frame) {
  takeWindow(r);
  if (window_) {
    const auto held = [](const Tracked& t) { return WindowKeyframe{t.cloud, t.index, t.pose}; };
    window_->enter(engine_, held(*keyframe_), held(frame), frame.to_keyframe,
                   frame.to_keyframe_covariance);
  }
  frame.to_keyframe = Eigen::Isometry3d::Identity();
  frame.to_keyframe_covariance = Matrix6d::Zero();
  keyframe_ = std::move(frame);
}

void Odometry::takeWindow(OdometryResult& r) {
  if (!window_) return;
  const auto t0 = Clock::now();
  const std::optional<WindowUpdate> update = window_->take();
  if (!update) return;
  r.ms_window_wait = msSince(t0);
  r.ms_window = update->ms_registration;
  r.window_links = update->links;
  r.window_shift = update->shift;
  r.window_shift_deg = update->shift_deg;
  // The frames from here on go on from the keyframe's refined pose; the one given out stays.
  for (std::optional<Tracked>* held : {&keyframe_, &last_}) {
    if (*held && (*held)->index == update->index) (*held)->pose = update->pose;
  }
}

}  // namespace acvo
