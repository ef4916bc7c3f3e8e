// acvo_synth: writes a synthetic RGB-D sequence with exact ground truth as a TUM-format folder.
#include <unistd.h>

#include <charconv>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "synth/sequence.hpp"

namespace {

constexpr const char* kUsage = R"(usage: acvo_synth OUTPUT_DIR [options]

Renders a synthetic RGB-D sequence of a procedural room with exactly known camera poses and
writes it as a TUM RGB-D folder: rgb/<stamp>.png, depth/<stamp>.png (16-bit, 5000 per metre,
0 = invalid), rgb.txt, depth.txt, associations.txt, groundtruth.txt (camera-to-world,
"timestamp tx ty tz qx qy qz qw") and camera.yaml. The same options give identical files.

options (default in brackets):
  --frames N             number of frames [300]
  --rate HZ              frame rate; stamps are 1000 + i / rate [30]
  --motion KIND          random | xyz | rpy | circle | still | sway [random]
  --speed M_PER_S        mean linear speed; angular speed follows (80 deg/s per m/s) [0.3]
  --seed N               scene, motion and noise seed [1]
  --structure on|off     furnished room, or a single plane filling the view [on]
  --texture on|off       procedural multi-scale textures, or flat colours [on]
  --noise on|off         Kinect-like depth noise, quantisation, dropouts; colour noise [on]
  --blur on|off          motion blur (mean of sub-frame renders over half a frame) [off]
  --width W --height H   image size; the 640x480 intrinsics (525, 525, 319.5, 239.5) scale
                         with it [640 480]
  -h, --help             this text
)";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

template <typename T>
T parseNumber(const std::string& option, const std::string& text) {
  T value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size())
    throw UsageError(option + " expects a number, got '" + text + "'");
  return value;
}

bool parseSwitch(const std::string& option, const std::string& text) {
  if (text == "on") return true;
  if (text == "off") return false;
  throw UsageError(option + " expects on or off, got '" + text + "'");
}

struct Arguments {
  std::string output;
  acvo::synth::SequenceOptions options;
  bool help = false;
};

Arguments parseArguments(int argc, char** argv) {
  Arguments args;
  int width = 640, height = 480;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    std::string option = argv[i];
    if (option == "-h" || option == "--help") {
      args.help = true;
      return args;
    }
    if (option.rfind("--", 0) != 0 || option.size() == 2) {
      positional.push_back(option);
      continue;
    }
    std::string value;
    if (const auto eq = option.find('='); eq != std::string::npos) {
      value = option.substr(eq + 1);
      option.resize(eq);
    } else {
      if (i + 1 >= argc) throw UsageError(option + " needs a value");
      value = argv[++i];
    }
    auto& o = args.options;
    if (option == "--frames") {
      o.frames = parseNumber<int>(option, value);
      if (o.frames < 1) throw UsageError("--frames must be at least 1");
    } else if (option == "--rate") {
      o.rate = parseNumber<double>(option, value);
      if (!(o.rate > 0) || o.rate > 1e6) throw UsageError("--rate must be within (0, 1e6] Hz");
    } else if (option == "--motion") {
      const auto kind = acvo::synth::parseMotionKind(value);
      if (!kind)
        throw UsageError("--motion expects random, xyz, rpy, circle, still or sway, got '" + value +
                         "'");
      o.motion = *kind;
    } else if (option == "--speed") {
      o.speed = parseNumber<double>(option, value);
      if (!(o.speed >= 0) || o.speed > 10) throw UsageError("--speed must be within [0, 10] m/s");
    } else if (option == "--seed") {
      o.seed = parseNumber<unsigned long long>(option, value);
    } else if (option == "--structure") {
      o.structure = parseSwitch(option, value);
    } else if (option == "--texture") {
      o.texture = parseSwitch(option, value);
    } else if (option == "--noise") {
      o.noise = parseSwitch(option, value);
    } else if (option == "--blur") {
      o.blur = parseSwitch(option, value);
    } else if (option == "--width" || option == "--height") {
      const int size = parseNumber<int>(option, value);
      if (size < 8 || size > 8192) throw UsageError(option + " must be within [8, 8192] pixels");
      (option == "--width" ? width : height) = size;
    } else {
      throw UsageError("unknown option " + option);
    }
  }
  if (positional.size() != 1)
    throw UsageError(positional.empty() ? "missing OUTPUT_DIR" : "more than one OUTPUT_DIR given");
  args.output = positional.front();
  args.options.camera = acvo::synth::scaledDefaultCamera(width, height);
  return args;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  try {
    args = parseArguments(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "acvo_synth: " << e.what() << "\nTry 'acvo_synth --help'.\n";
    return 2;
  }
  if (args.help) {
    std::cout << kUsage;
    return 0;
  }

  const bool show_progress = isatty(fileno(stderr));
  const auto started = std::chrono::steady_clock::now();
  try {
    acvo::synth::writeSequence(args.output, args.options, [&](int done, int total) {
      if (show_progress) std::cerr << "\racvo_synth: frame " << done << "/" << total << std::flush;
    });
  } catch (const std::exception& e) {
    if (show_progress) std::cerr << "\n";
    std::cerr << "acvo_synth: " << e.what() << "\n";
    return 1;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (show_progress) std::cerr << "\n";
  std::cout << "acvo_synth: wrote " << args.options.frames << " frames ("
            << args.options.camera.width << "x" << args.options.camera.height << ") to "
            << args.output << " in " << seconds << " s\n";
  return 0;
}
