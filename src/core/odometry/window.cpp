// The odometry's local window of keyframes (odometry.hpp, window.hpp, docs/method.md §7.7).
#include <algorithm>
#include <unordered_map>

#include "acvo/odometry/odometry.hpp"
#include "acvo/odometry/window.hpp"

namespace acvo {

void Odometry::newKeyframe(OdometryResult& r, Tracked frame) {
  enterWindow(r, frame);
  frame.to_keyframe = Eigen::Isometry3d::Identity();
  frame.to_keyframe_covariance = Matrix6d::Zero();
  keyframe_ = std::move(frame);
}

void Odometry::enterWindow(OdometryResult& r, Tracked& frame) {
  const auto size = std::size_t(std::max(params_.odometry.window_keyframes, 0));
  if (size <= 2 || params_.odometry.reference != Reference::kKeyframe) return;
  // The window holds the keyframes linked to one another since the last start or loss.
  if (window_.empty() || window_.back().index != keyframe_->index) {
    window_.assign(1, *keyframe_);
    links_.clear();
    anchors_.clear();
  }
  const std::optional<Matrix6d> to_keyframe =
      scaledInverseInformation(frame.to_keyframe_covariance, 1.0);
  if (!to_keyframe) {  // not constrained in every direction: the window starts again
    window_.clear();
    return;
  }
  links_.push_back({keyframe_->index, frame.index, frame.to_keyframe, *to_keyframe});
  r.window_links = 1;
  linkToOlderKeyframes(r, frame);
  window_.push_back(frame);
  leaveWindow(size);
  refineWindow(frame);
  const Eigen::Isometry3d shift = r.pose.inverse() * frame.pose;
  r.window_shift = shift.translation().norm();
  r.window_shift_deg = rotationDeg(shift);
}

void Odometry::linkToOlderKeyframes(OdometryResult& r, const Tracked& frame) {
  // The current keyframe (the last) is linked already.
  for (auto older = window_.rbegin() + 1; older != window_.rend(); ++older) {
    // From where the poses put it, a few millimetres off: the finest level alone, whose narrow
    // kernel holds the still part of the view where the coarse levels' wide one could follow a
    // person moving in it (as a second start does, second_start.hpp).
    const Eigen::Isometry3d guess = older->pose.inverse() * frame.pose;
    const SolverResult s = alignInArena(*older->cloud, *frame.cloud, guess, AlignStages::kFinest);
    r.ms_window += s.ms_total;
    // The registration must be one a frame would be tracked by, and move the pose no more than
    // a frame may move.
    const Judgement judgement = judgeTracking(s, guess.inverse() * s.transform, params_.odometry);
    if (judgement.tracking != Tracking::kOk) continue;
    // It says where the keyframe's centre lies, not how it is turned: on a real camera a
    // registration across several keyframes errs in rotation with its span, more than the chain
    // of shorter ones does (its depth's distortion is fixed in the image).
    const std::optional<Matrix6d> covariance = engine_->covariance(s, frame.cloud->size());
    const std::optional<Matrix6d> information =
        covariance ? centreInformation(*covariance, s.transform) : std::nullopt;
    if (!information) continue;
    links_.push_back({older->index, frame.index, s.transform, *information});
    ++r.window_links;
  }
}

void Odometry::leaveWindow(std::size_t size) {
  // The oldest keyframes leave with the poses they have: each keeps holding the keyframes it is
  // linked to, as long as they are in the window.
  while (window_.size() > size) {
    anchors_.emplace_back(window_.front().index, window_.front().pose);
    window_.pop_front();
  }
  const auto in_window = [this](std::uint64_t index) {
    return std::any_of(window_.begin(), window_.end(),
                       [index](const Tracked& k) { return k.index == index; });
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

void Odometry::refineWindow(Tracked& frame) {
  // The keyframes that left the window first, held; without them, the oldest in it.
  std::unordered_map<std::uint64_t, int> position;
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& [index, pose] : anchors_) {
    position[index] = int(poses.size());
    poses.push_back(pose);
  }
  for (const Tracked& k : window_) {
    position[k.index] = int(poses.size());
    poses.push_back(k.pose);
  }
  std::vector<WindowLink> links;
  for (const Link& l : links_) {
    links.push_back({position.at(l.fixed), position.at(l.moving), l.measured, l.information});
  }
  const int held = anchors_.empty() ? 1 : int(anchors_.size());
  acvo::refineWindow(poses, links, held);
  for (std::size_t k = 0; k < window_.size(); ++k) window_[k].pose = poses[anchors_.size() + k];
  frame.pose = poses.back();
}

}  // namespace acvo
