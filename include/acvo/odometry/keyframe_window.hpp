// The odometry's local window of keyframes (docs/method.md §7.7; its math in window.hpp): each
// new keyframe is registered to the older keyframes in the window, and the window's poses are
// refined together over those registrations, the oldest held.
//
// That work for a keyframe runs after the keyframe's pose was given out, on a thread of its own
// where the engine allows it (RegistrationEngine::reentrant), while the next frame is registered;
// the next frame takes the keyframe's refined pose (take()) before composing its own. Without a
// second thread the work runs in take(), and the poses are the same either way.
#pragma once

#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "acvo/math/se3.hpp"
#include "acvo/odometry/window.hpp"
#include "acvo/params.hpp"
#include "acvo/registration/engine.hpp"

namespace acvo {

// A keyframe as the window holds it: its cloud (prepared as a reference) and its pose.
struct WindowKeyframe {
  std::shared_ptr<const PreparedCloud> cloud;
  std::uint64_t index = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // camera in the odometry frame
};

// What the window's work did for one keyframe.
struct WindowUpdate {
  std::uint64_t index = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // refined
  double ms_registration = 0.0;  // its registrations to the older keyframes
  int links = 0;       // its links to older keyframes, the one to the keyframe before included
  double shift = 0.0;  // how far the refinement moved it from its given pose (m, deg)
  double shift_deg = 0.0;
};

// The threads of a solver's pool for OdometryParams::threads (-1: all cores but one, 0: all).
int solverThreads(int setting);

class KeyframeWindow {
 public:
  // `size`: the keyframes in the window, the new one included (> 2). `threads`: the solver's
  // (OdometryParams::threads), for the window's own thread pool.
  KeyframeWindow(std::size_t size, const OdometryParams& params, int threads);
  ~KeyframeWindow();  // waits for the work in flight
  KeyframeWindow(const KeyframeWindow&) = delete;
  KeyframeWindow& operator=(const KeyframeWindow&) = delete;

  // `frame`, registered to `keyframe` by `to_keyframe` (T: frame -> keyframe) with `covariance`,
  // becomes the newest keyframe: its work starts. The window starts again from `keyframe` where
  // `keyframe` is not its newest (after a loss or a reset), and is emptied where the registration
  // does not constrain every direction. Takes up the work in flight first (its update is lost:
  // call take() before).
  void enter(std::shared_ptr<const RegistrationEngine> engine, const WindowKeyframe& keyframe,
             const WindowKeyframe& frame, const Eigen::Isometry3d& to_keyframe,
             const Matrix6d& covariance);
  // The last entered keyframe's update, waiting for its work where it runs yet; nullopt where
  // there is none, or it was taken already.
  std::optional<WindowUpdate> take();
  // Waits for the work in flight and forgets every keyframe.
  void clear();

 private:
  using Link = LinkBetween<std::uint64_t>;
  WindowUpdate work(const RegistrationEngine& engine, WindowKeyframe frame);
  void linkToOlderKeyframes(const RegistrationEngine& engine, const WindowKeyframe& frame,
                            WindowUpdate& update);
  void leave();
  Eigen::Isometry3d refine();

  std::size_t size_;
  OdometryParams params_;
  // The keyframes, oldest first, the newest last; the registrations linking them, by frame
  // index; and keyframes that left the window, with their last poses, held fixed while a
  // keyframe in the window is linked to them. Only the work touches them while it runs.
  std::deque<WindowKeyframe> keyframes_;
  std::vector<Link> links_;
  std::vector<std::pair<std::uint64_t, Eigen::Isometry3d>> anchors_;
  struct Arena;
  std::unique_ptr<Arena> arena_;
  std::future<WindowUpdate> pending_;  // last: waited for before the rest is destroyed
};

}  // namespace acvo
