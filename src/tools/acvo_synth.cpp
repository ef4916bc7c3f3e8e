// acvo_synth: writes a synthetic RGB-D sequence with exact ground truth as a TUM-format folder.
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>

#include "synth/sequence.hpp"
#include "tool_support.hpp"

namespace {

constexpr const char* kDescription =
    R"(Renders a synthetic RGB-D sequence of a procedural room with exactly known camera poses and
writes it as a TUM RGB-D folder: rgb/<stamp>.png, depth/<stamp>.png (16-bit, 5000 per metre,
0 = invalid), rgb.txt, depth.txt, associations.txt, groundtruth.txt (camera-to-world,
"timestamp tx ty tz qx qy qz qw") and camera.yaml. The same options give identical files.
)";

constexpr const char* kFooter =
    "Exit status: 0 success, 1 the folder could not be written, 2 bad arguments.";

// An on|off option (the switches of the scene and the renderer).
CLI::Option* addSwitch(CLI::App& app, const std::string& name, bool& value,
                       const std::string& help) {
  return app
      .add_option_function<std::string>(
          name, [&value](const std::string& text) { value = text == "on"; }, help)
      ->check(CLI::IsMember({"on", "off"}).description(""))
      ->type_name("on|off")
      ->default_str(value ? "on" : "off");
}

// The scene, the camera's path and the renderer's switches.
void addSceneOptions(CLI::App& app, acvo::synth::SequenceOptions& o) {
  app.add_option("--frames", o.frames, "number of frames (at least 1)")
      ->type_name("N")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(1, std::numeric_limits<int>::max(), "at least 1"));
  app.add_option("--rate", o.rate, "frame rate; stamps are 1000 + i / rate")
      ->type_name("HZ")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(std::numeric_limits<double>::denorm_min(), 1e6,
                                        "within (0, 1e6] Hz"));
  app.add_option_function<std::string>(
         "--motion",
         [&o](const std::string& kind) { o.motion = *acvo::synth::parseMotionKind(kind); },
         "camera motion: random, xyz, rpy, circle, still or sway")
      ->check(CLI::IsMember({"random", "xyz", "rpy", "circle", "still", "sway"}).description(""))
      ->type_name("KIND")
      ->default_str(acvo::synth::toString(o.motion));
  app.add_option("--speed", o.speed, "mean linear speed; angular speed follows (80 deg/s per m/s)")
      ->type_name("M_PER_S")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(0.0, 10.0, "within [0, 10] m/s"));
  app.add_option("--seed", o.seed, "scene, motion and noise seed")
      ->type_name("N")
      ->capture_default_str()
      ->transform(acvo::tools::anyNumber<std::uint64_t>());
  addSwitch(app, "--structure", o.structure, "furnished room, or a single plane filling the view");
  addSwitch(app, "--texture", o.texture, "procedural multi-scale textures, or flat colours");
  addSwitch(app, "--noise", o.noise,
            "Kinect-like depth noise, quantisation, dropouts; colour noise");
  addSwitch(app, "--blur", o.blur, "motion blur (mean of sub-frame renders over half a frame)");
}

// What a real camera does to the images: a second colour camera, unsynchronised streams, auto
// exposure, a lens, a structured-light sensor's depth, a person in view.
void addCameraFaults(CLI::App& app, acvo::synth::SequenceOptions& o) {
  app.add_option("--colour-focal-ratio", o.colour_focal_ratio,
                 "an unregistered colour camera: its focal length over the depth camera's "
                 "(7-Scenes: about 525/585)")
      ->type_name("R")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(0.5, 2.0, "within [0.5, 2]"));
  app.add_option("--colour-baseline", o.colour_baseline,
                 "an unregistered colour camera: its offset along x from the depth camera "
                 "(a Kinect's: 0.025 m)")
      ->type_name("M")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(-1.0, 1.0, "within [-1, 1] m"));
  app.add_option("--colour-delay", o.colour_delay,
                 "colour taken S seconds after the depth (negative: before), as unsynchronised "
                 "streams (a Kinect v1's, a RealSense's): rendered at that time's pose and "
                 "stamped with it; under half a frame interval")
      ->type_name("S")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(-0.1, 0.1, "within [-0.1, 0.1] s"));
  app.add_option("--brightness-swing", o.brightness_swing,
                 "a camera's auto exposure: the colour's brightness swings smoothly by up to "
                 "this fraction either way (0.2: +-20%, up to 2% a frame at 30 Hz)")
      ->type_name("A")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(0.0, 0.9, "within [0, 0.9]"));
  app.add_option("--vignetting", o.vignetting,
                 "a lens's darkening towards the corners: the colour times exp(V rho), rho the "
                 "squared distance from the principal point in focal lengths (-1: 43% darker at "
                 "a 640x480 image's corners)")
      ->type_name("V")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(-3.0, 0.0, "within [-3, 0]"));
  app.add_option("--depth-noise-correlation", o.depth_noise_correlation,
                 "the depth noise in blobs of neighbouring pixels that err together, as a "
                 "structured-light sensor's (its pattern is matched over a window): their "
                 "correlation length in pixels (4: neighbours 10 px apart correlate by 0.2); 0: "
                 "each pixel's own")
      ->type_name("PX")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(0.0, 50.0, "within [0, 50] pixels"));
  app.add_option("--depth-distortion", o.depth_distortion,
                 "a sensor's fixed depth distortion: every frame's depth scaled by 1 + R D(u,v), "
                 "D a smooth unit field fixed to the image (a few per mille: an uncalibrated "
                 "structured-light sensor); 0: none")
      ->type_name("R")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(0.0, 0.05, "within [0, 0.05]"));
  app.add_option("--walker", o.walker_speed,
                 "a person (a box of a person's size, 1.2 m in front of the start) walking back "
                 "and forth across the view at this speed, the scene's one moving object, as in "
                 "TUM's dynamic sequences (a person walks at 1-1.4 m/s); 0: none. Needs "
                 "--structure on")
      ->type_name("M_PER_S")
      ->capture_default_str()
      ->transform(acvo::tools::numberIn(0.0, 5.0, "within [0, 5] m/s"));
}

// Renders and writes the sequence: 0, or the tool's exit status for a failure.
int write(const CLI::App& app, const std::string& output, const acvo::synth::SequenceOptions& o) {
  const bool show_progress = isatty(fileno(stderr));
  const auto started = std::chrono::steady_clock::now();
  try {
    acvo::synth::writeSequence(output, o, [&](int done, int total) {
      if (show_progress) std::cerr << "\racvo_synth: frame " << done << "/" << total << std::flush;
    });
  } catch (const std::invalid_argument& e) {
    // Options that do not go together (SequenceOptions' own check, before any file is made,
    // e.g. --colour-delay over half a frame at --rate): a usage error, as a bad option is.
    return acvo::tools::usageError(app, e.what());
  } catch (const std::exception& e) {
    if (show_progress) std::cerr << "\n";
    std::cerr << "acvo_synth: " << e.what() << "\n";
    return 1;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (show_progress) std::cerr << "\n";
  std::cout << "acvo_synth: wrote " << o.frames << " frames (" << o.camera.width << "x"
            << o.camera.height << ") to " << output << " in " << seconds << " s\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string output;
  acvo::synth::SequenceOptions o;
  int width = 640, height = 480;
  CLI::App app{kDescription, "acvo_synth"};
  acvo::tools::setUpCommandLine(app, kFooter);
  app.add_option("OUTPUT_DIR", output, "the folder to write")->type_name("")->required();
  addSceneOptions(app, o);
  addCameraFaults(app, o);
  const auto size = acvo::tools::numberIn(8, 8192, "within [8, 8192] pixels");
  app.add_option("--width", width, "image width; the 640x480 intrinsics scale with the size")
      ->type_name("W")
      ->capture_default_str()
      ->transform(size);
  app.add_option("--height", height, "image height")
      ->type_name("H")
      ->capture_default_str()
      ->transform(size);
  if (const auto status = acvo::tools::parseCommandLine(app, argc, argv)) return *status;
  o.camera = acvo::synth::scaledDefaultCamera(width, height);
  return write(app, output, o);
}
