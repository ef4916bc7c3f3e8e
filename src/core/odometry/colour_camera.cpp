// What is done about a colour camera that is not the depth camera (colour_camera.hpp), and the
// odometry's side of it: the check's frames, the engine for its verdict, the keyframe rebuilt
// from the resampled colour.
#include "acvo/odometry/colour_camera.hpp"

#include <string>

#include "acvo/odometry/odometry.hpp"

namespace acvo {

bool ColourCamera::look(const Frame& as_registered, std::uint64_t frame_index) {
  if (check_.decided() || frame_index % ColourDepthCheck::kFrameStep != 0) return false;
  check_.add(as_registered);
  if (!check_.decided()) return false;
  take(check_);
  return true;
}

void ColourCamera::take(const ColourDepthCheck& check) {
  check_ = check;
  ratio_.reset();
  const ColourDepthCheck::Verdict& v = check_.verdict();
  if (v.state == ColourDepthCheck::State::kUnregistered && act_ != UnregisteredColour::kAsGiven) {
    ratio_ = v.best_ratio;
  }
}

Frame ColourCamera::prepared(const Frame& frame) const {
  return ratio_ ? withColourResampled(frame, *ratio_) : frame;
}

Params ColourCamera::engineParams(const Params& params) const {
  Params p = params;
  if (ratio_ && act_ == UnregisteredColour::kResampleDepthLed) {
    p.coarse_to_fine.photometric = false;
    p.coarse_to_fine.depth_led = true;
  }
  return p;
}

std::string ColourCamera::describe() const {
  std::string text = check_.describe();
  if (!ratio_) return text;
  return text + (act_ == UnregisteredColour::kResampleDepthLed
                     ? ". Meanwhile each frame's colour is resampled by that ratio, and registered "
                       "without the photometric term, led by the depth "
                       "(odometry/unregistered_colour: resample_depth_led)"
                     : ". Meanwhile each frame's colour is resampled by that ratio "
                       "(odometry/unregistered_colour: resample)");
}

// The odometry's side (odometry.hpp).

Frame depthAsRegistered(const Frame& frame, const OdometryResult& r) {
  if (!r.cloud || r.cloud->depth.empty()) return frame;
  Frame out = frame;
  out.depth = r.cloud->depth;
  return out;
}

void Odometry::lookAtColour(const Frame& frame, OdometryResult& r) {
  if (r.tracking == Tracking::kBadFrame) return;
  const bool had = colour_.ratio().has_value();
  if (!colour_.look(depthAsRegistered(frame, r), r.frame_index)) return;
  r.colour_verdict_now = true;
  if (had != colour_.ratio().has_value()) makeEngine();
  if (!colour_.ratio() || !last_ || last_->index != r.frame_index) return;
  // This frame becomes the keyframe, its cloud built again from its colour resampled: the next
  // frame, resampled, registered to a keyframe of colour as it came would pair each texture
  // with where it was not.
  OdometryResult again;
  Tracked rebuilt = *last_;
  rebuilt.cloud = asReference(again, buildCloud(colour_.prepared(frame), again));
  rebuilt.to_keyframe = Eigen::Isometry3d::Identity();
  rebuilt.to_keyframe_covariance = Matrix6d::Zero();
  keyframe_ = last_ = rebuilt;
  r.new_keyframe = true;
  r.ms_cloud += again.ms_cloud;
  r.ms_prepare += again.ms_prepare;
}

void Odometry::makeEngine() {
  // A keyframe prepared by the other engine serves either (the dense term waits for a keyframe
  // with a depth grid); the verdict's frame is rebuilt as the keyframe (lookAtColour).
  engine_ = makeRegistrationEngine(engineParams());
}

std::string Odometry::describeColour() const {
  std::string text = colour_.describe();
  const std::string changed = describeChanges(params_, engineParams(), '/');
  if (!changed.empty()) text += "; the engine's parameters now: " + changed;
  return text;
}

void Odometry::newCamera() { takeColourCheck(ColourDepthCheck()); }

void Odometry::takeColourCheck(const ColourDepthCheck& check) {
  const bool had = colour_.ratio().has_value();
  colour_.take(check);
  if (had != colour_.ratio().has_value()) makeEngine();
}

}  // namespace acvo
