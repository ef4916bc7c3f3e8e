// acvo_soak: a long synthetic sequence through acvo::Odometry in one process, with injected
// faults, reporting memory growth, time per frame and tracking figures. Too long for CI: run it
// by hand (scripts/soak) after changes to the odometry pipeline.
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "acvo/odometry.hpp"
#include "synth/sequence.hpp"
#include "tool_support.hpp"

namespace {

constexpr const char* kUsage = R"(usage: acvo_soak [options]

Streams synthetic RGB-D frames (the textured room, random handheld motion at 30 Hz, Kinect
noise) through acvo::Odometry and prints, every 1000 frames, the resident memory (VmRSS);
at the end: frames processed, tracking counts, RSS growth per 1000 frames after a warm-up of
1000 frames, median / p90 time per frame of Odometry::process, and the largest pose translation.
After the first --fault-every frames, every period of --fault-every frames carries five faults,
evenly spaced: a blank frame (black, no depth), a frame with all-zero depth, a frame with all-NaN
depth, a 1 s blackout of blank frames, a stamp going backwards. Exit status 1 when a pose is not
finite or processing throws.

options (default in brackets):
  --frames N           frames to process [10000]
  --fault-every N      period of the five injected faults in frames, 0 = none [500]
  --width W --height H image size (intrinsics scaled from 640x480) [640 480]
  --seed N             scene, motion and noise seed [1]
  -h, --help           this text
)";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Arguments {
  int frames = 10000;
  int fault_every = 500;
  int width = 640, height = 480;
  unsigned seed = 1;
  bool help = false;
};

template <typename T>
T parseNumber(const std::string& option, const std::string& text) {
  T value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size()) {
    throw UsageError(option + " expects a number, got '" + text + "'");
  }
  return value;
}

Arguments parseArguments(int argc, char** argv) {
  Arguments a;
  for (int k = 1; k < argc; ++k) {
    const std::string option = argv[k];
    if (option == "-h" || option == "--help") {
      a.help = true;
      continue;
    }
    if (k + 1 >= argc) throw UsageError("unknown option or missing value: " + option);
    const std::string value = argv[++k];
    if (option == "--frames") {
      a.frames = parseNumber<int>(option, value);
    } else if (option == "--fault-every") {
      a.fault_every = parseNumber<int>(option, value);
    } else if (option == "--width") {
      a.width = parseNumber<int>(option, value);
    } else if (option == "--height") {
      a.height = parseNumber<int>(option, value);
    } else if (option == "--seed") {
      a.seed = parseNumber<unsigned>(option, value);
    } else {
      throw UsageError("unknown option " + option);
    }
  }
  if (a.frames < 1) throw UsageError("--frames must be at least 1");
  if (a.fault_every < 0) throw UsageError("--fault-every must not be negative");
  if (a.width < 16 || a.height < 16) throw UsageError("--width and --height must be at least 16");
  return a;
}

enum class Fault { kNone, kBlank, kZeroDepth, kNanDepth, kBlackout, kStampBack };

const char* toString(Fault f) {
  switch (f) {
    case Fault::kNone:
      return "none";
    case Fault::kBlank:
      return "blank frame";
    case Fault::kZeroDepth:
      return "all-zero depth";
    case Fault::kNanDepth:
      return "NaN depth";
    case Fault::kBlackout:
      return "1 s blackout";
    case Fault::kStampBack:
      return "stamp backwards";
  }
  return "?";
}

// Which fault (if any) frame i carries: after the first `every` frames, each period of `every`
// frames holds the five faults in turn, `every` / 5 frames apart; a blackout lasts
// `blackout_frames` frames.
Fault faultAt(int i, int every, int blackout_frames) {
  if (every <= 0 || i < every) return Fault::kNone;
  constexpr Fault kCycle[] = {Fault::kBlank, Fault::kZeroDepth, Fault::kNanDepth, Fault::kBlackout,
                              Fault::kStampBack};
  const int spacing = std::max(every / 5, 1);
  const int k = i % every;
  if (k % spacing == 0 && k / spacing < 5) return kCycle[k / spacing];
  const int blackout_start = 3 * spacing;
  return k > blackout_start && k < blackout_start + blackout_frames ? Fault::kBlackout
                                                                    : Fault::kNone;
}

acvo::Frame inject(acvo::Frame frame, Fault fault, double previous_stamp) {
  switch (fault) {
    case Fault::kNone:
      break;
    case Fault::kBlank:
    case Fault::kBlackout:
      frame.color.setTo(cv::Scalar::all(0));
      frame.depth.setTo(cv::Scalar(0.0));
      break;
    case Fault::kZeroDepth:
      frame.depth.setTo(cv::Scalar(0.0));
      break;
    case Fault::kNanDepth:
      frame.depth.setTo(cv::Scalar(std::numeric_limits<double>::quiet_NaN()));
      break;
    case Fault::kStampBack:
      frame.stamp = previous_stamp - 0.5;
      break;
  }
  return frame;
}

// Least-squares slope of y over x (0 with fewer than two samples).
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 2) return 0.0;
  double mx = 0, my = 0;
  for (std::size_t k = 0; k < n; ++k) mx += x[k] / n, my += y[k] / n;
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < n; ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  return sxx > 0 ? sxy / sxx : 0.0;
}

int run(const Arguments& args) {
  acvo::synth::SequenceOptions o;
  o.frames = args.frames;
  o.seed = args.seed;
  o.camera = acvo::synth::scaledDefaultCamera(args.width, args.height);
  const acvo::synth::SynthSequence sequence(o);
  const int blackout_frames = static_cast<int>(std::lround(o.rate));  // 1 s

  std::printf("acvo_soak: %d frames %dx%d at %g Hz, faults every %d frames\n", args.frames,
              args.width, args.height, o.rate, args.fault_every);
  acvo::Odometry odometry;
  constexpr int kWarmup = 1000, kReportEvery = 1000, kSampleEvery = 100;
  std::vector<double> ms, rss_frame, rss_kib;
  ms.reserve(args.frames);
  int counts[5] = {}, lost_on_faults = 0, fault_frames = 0;
  double max_translation = 0.0;
  bool all_finite = true;
  const long rss_start = acvo::tools::residentKiB();
  double previous_stamp = 0.0;

  for (int i = 0; i < args.frames; ++i) {
    const Fault fault = faultAt(i, args.fault_every, blackout_frames);
    const acvo::Frame frame = inject(sequence.frame(i).toFrame(), fault, previous_stamp);
    previous_stamp = frame.stamp;

    const auto t0 = std::chrono::steady_clock::now();
    const acvo::OdometryResult r = odometry.process(frame);
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());

    ++counts[static_cast<int>(r.tracking)];
    if (fault != Fault::kNone) {
      ++fault_frames;
      lost_on_faults += r.tracking == acvo::Tracking::kLost;
    }
    if (!r.pose.matrix().allFinite() || !r.motion.matrix().allFinite()) {
      if (all_finite) std::printf("frame %d: pose not finite (fault: %s)\n", i, toString(fault));
      all_finite = false;
    } else {
      max_translation = std::max(max_translation, r.pose.translation().norm());
    }

    const int done = i + 1;
    if (done % kSampleEvery == 0 && done >= kWarmup) {
      rss_frame.push_back(done);
      rss_kib.push_back(static_cast<double>(acvo::tools::residentKiB()));
    }
    if (done % kReportEvery == 0) {
      std::printf("frame %6d  rss %8ld KiB  lost %5d  hard %5d  ok %6d  median %.1f ms\n", done,
                  acvo::tools::residentKiB(), counts[int(acvo::Tracking::kLost)],
                  counts[int(acvo::Tracking::kHard)], counts[int(acvo::Tracking::kOk)],
                  acvo::tools::percentile(ms, 0.5));
      std::fflush(stdout);
    }
  }

  const long rss_end = acvo::tools::residentKiB();
  std::printf("\nframes processed: %d (%d carried a fault)\n", args.frames, fault_frames);
  std::printf("tracking: ok %d, hard %d, lost %d (%d of them on fault frames), first %d, bad %d\n",
              counts[int(acvo::Tracking::kOk)], counts[int(acvo::Tracking::kHard)],
              counts[int(acvo::Tracking::kLost)], lost_on_faults,
              counts[int(acvo::Tracking::kFirstFrame)], counts[int(acvo::Tracking::kBadFrame)]);
  // The samples above are taken with a frame's images alive; these two between frames.
  std::printf("RSS: %ld KiB before the first frame, %ld KiB after the last\n", rss_start, rss_end);
  if (rss_kib.size() >= 2) {
    std::printf(
        "RSS growth after %d frames of warm-up: %.1f KiB per 1000 frames (fit over %zu "
        "samples, frames %.0f-%.0f)\n",
        kWarmup, 1000.0 * slope(rss_frame, rss_kib), rss_kib.size(), rss_frame.front(),
        rss_frame.back());
  } else {
    std::printf("RSS growth: n/a (needs more than %d frames)\n", kWarmup + kSampleEvery);
  }
  std::printf("Odometry::process: median %.1f ms, p90 %.1f ms, max %.1f ms per frame\n",
              acvo::tools::percentile(ms, 0.5), acvo::tools::percentile(ms, 0.9),
              *std::max_element(ms.begin(), ms.end()));
  std::printf("max |pose translation|: %.3f m; all poses finite: %s\n", max_translation,
              all_finite ? "yes" : "NO");
  return all_finite ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Arguments args = parseArguments(argc, argv);
    if (args.help) {
      std::cout << kUsage;
      return 0;
    }
    return run(args);
  } catch (const UsageError& e) {
    std::cerr << "acvo_soak: " << e.what() << "\n\n" << kUsage;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "acvo_soak: " << e.what() << "\n";
    return 1;
  }
}
