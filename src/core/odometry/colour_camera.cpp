// What is done about a colour camera that is not the depth camera (colour_camera.hpp).
#include "acvo/odometry/colour_camera.hpp"

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

}  // namespace acvo
