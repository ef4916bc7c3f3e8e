// What the odometry does about the colour camera (OdometryParams::unregistered_colour): it gives
// the colour check (ColourDepthCheck) its frames until the check decides, and once the check
// finds the depth not registered to the colour (a second camera's colour: a driver's raw depth,
// 7-Scenes' recordings), resamples each frame's colour to the depth camera by the focal ratio
// found, and, with resample_depth_led, registers without the photometric term, the last level
// led by the depth: resampled by the focal ratio, a point's colour is still off by the cameras'
// baseline (a few pixels), near enough for the labels and the selection, too far for grey values
// compared at a sub-pixel; without the grey values the depth's plane terms must correct the
// kernel's pull towards no motion on real depth (CoarseToFineParams::depth_led).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "acvo/cloud/colour_depth_check.hpp"
#include "acvo/cloud/frame.hpp"
#include "acvo/params.hpp"

namespace acvo {

class ColourCamera {
 public:
  explicit ColourCamera(UnregisteredColour act = UnregisteredColour::kResampleDepthLed)
      : act_(act) {}

  // Gives the frame (colour and depth as registered: depthAsRegistered) to the check when its
  // turn comes (every ColourDepthCheck::kFrameStep-th frame until it decides); true when the
  // verdict became known with it.
  bool look(const Frame& as_registered, std::uint64_t frame_index);
  // Takes over a check made on this camera (before a parameter change), or a new one.
  void take(const ColourDepthCheck& check);

  // The focal ratio each frame's colour is resampled by, once unregistered (none otherwise).
  const std::optional<double>& ratio() const { return ratio_; }
  // The frame as it is registered: its colour resampled by ratio(), as it came without one.
  Frame prepared(const Frame& frame) const;
  // The parameters the registration engine runs with while the verdict lasts: `params`, or with
  // photometric off and depth_led on (resample_depth_led, a ratio found).
  Params engineParams(const Params& params) const;
  const ColourDepthCheck& check() const { return check_; }
  // The check's verdict for a log (ColourDepthCheck::describe), and what is done about it.
  std::string describe() const;

 private:
  UnregisteredColour act_;
  ColourDepthCheck check_;
  std::optional<double> ratio_;
};

}  // namespace acvo
