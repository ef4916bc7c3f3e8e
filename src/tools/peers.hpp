// The peers acvo is measured against: OpenCV contrib's RGB-D odometries (RgbdOdometry,
// ICPOdometry, RgbdICPOdometry) run frame to frame the way OpenCV's own TUM sample runs them
// (opencv_contrib modules/rgbd/samples/odometry_evaluation.cpp): depth in metres with missing
// depth as NaN, grey images, compute(current, previous) so that Rt maps the current camera's
// points into the previous one's, no initial guess, a failed frame keeps the last pose. What a
// user would tune is a setting here (the maximum depth); the set-up faults a sanity test must
// catch (holes as zeros, the motion inverted, millimetres taken for metres) can be switched on.
#pragma once

#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "acvo/cloud/camera.hpp"
#include "acvo/cloud/frame.hpp"

namespace acvo::peers {

enum class PeerKind { kRgbd, kIcp, kRgbdIcp };

// Set-up faults that a comparison harness can make, each of which handicaps the peer: the
// sanity test (test_peers) checks that each one shows. All off in acvo_compare.
struct PeerFaults {
  bool holes_as_zeros = false;   // invalid depth given as 0 instead of NaN
  bool inverted_motion = false;  // Rt composed the wrong way round
  double depth_factor = 1.0;     // depth given to OpenCV = metres * depth_factor (1000: mm)
};

struct PeerSetup {
  PeerKind kind = PeerKind::kRgbd;
  double max_depth = 4.0;  // m, setMaxDepth (OpenCV's default 4)
  // compute(current, previous) as OpenCV's sample; false: compute(previous, current), Rt
  // inverted (the same motion, found from the other side).
  bool current_as_source = true;
  bool previous_motion_guess = false;  // the last Rt as the initial guess (the sample: none)
  PeerFaults faults;
};

// "rgbd", "icp", "rgbd_icp"; parsePeerKind throws std::invalid_argument for another name.
std::string toString(PeerKind kind);
PeerKind parsePeerKind(const std::string& name);
// The row name of a set-up: "rgbd@4m", "icp@10m", ...
std::string rowName(const PeerSetup& setup);

// One peer's frame-to-frame odometry over a sequence.
class PeerOdometry {
 public:
  PeerOdometry(const PeerSetup& setup, const Camera& camera, const Eigen::Isometry3d& start);
  ~PeerOdometry();
  PeerOdometry(PeerOdometry&&) noexcept;
  PeerOdometry& operator=(PeerOdometry&&) noexcept;

  // Registers `frame` to the previous one; returns false when OpenCV reports a failure (the
  // pose is then held). The first frame only starts the sequence (true).
  bool process(const Frame& frame);
  // Camera pose of the last frame (camera to world, optical frame).
  const Eigen::Isometry3d& pose() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace acvo::peers
