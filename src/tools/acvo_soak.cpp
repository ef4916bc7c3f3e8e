// acvo_soak: a long synthetic sequence through acvo::Odometry in one process, with injected
// faults, reporting memory growth, time per frame and tracking figures. Too long for CI: run it
// by hand (scripts/soak) after changes to the odometry pipeline.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "acvo/odometry/odometry.hpp"
#include "synth/sequence.hpp"
#include "tool_support.hpp"

namespace {

constexpr const char* kDescription =
    R"(Streams synthetic RGB-D frames (the textured room, random handheld motion at 30 Hz, Kinect
noise) through acvo::Odometry and prints, every 1000 frames, the resident memory (VmRSS);
at the end: frames processed, tracking counts, RSS growth per 1000 frames after a warm-up of
1000 frames, median / p90 time per frame of Odometry::process, and the largest pose translation.
After the first --fault-every frames, every period of --fault-every frames carries five faults,
evenly spaced: a blank frame (black, no depth), a frame with all-zero depth, a frame with all-NaN
depth, a 1 s blackout of blank frames, a stamp going backwards.
)";

constexpr const char* kFooter =
    "Exit status: 0 success, 1 a pose was not finite or processing threw, 2 bad arguments.";

struct Arguments {
  int frames = 10000;
  int fault_every = 500;
  int width = 640, height = 480;
  unsigned seed = 1;
};

// The command line into `a`; nullopt to go on, else the exit status.
std::optional<int> parseArguments(CLI::App& app, Arguments& a, int argc, char** argv) {
  using acvo::tools::numberIn;
  const int kIntMax = std::numeric_limits<int>::max();
  acvo::tools::setUpCommandLine(app, kFooter);
  app.add_option("--frames", a.frames, "frames to process")
      ->type_name("N")
      ->capture_default_str()
      ->transform(numberIn(1, kIntMax, "at least 1"));
  app.add_option("--fault-every", a.fault_every,
                 "period of the five injected faults in frames, 0 = none")
      ->type_name("N")
      ->capture_default_str()
      ->transform(numberIn(0, kIntMax, "a non-negative integer"));
  const auto size = numberIn(16, kIntMax, "at least 16 pixels");
  app.add_option("--width", a.width, "image size (intrinsics scaled from 640x480)")
      ->type_name("W")
      ->capture_default_str()
      ->transform(size);
  app.add_option("--height", a.height, "image height")
      ->type_name("H")
      ->capture_default_str()
      ->transform(size);
  app.add_option("--seed", a.seed, "scene, motion and noise seed")
      ->type_name("N")
      ->capture_default_str()
      ->transform(acvo::tools::anyNumber<unsigned>());
  return acvo::tools::parseCommandLine(app, argc, argv);
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

// What the soak saw, frame by frame.
struct Tally {
  static constexpr int kWarmup = 1000, kReportEvery = 1000, kSampleEvery = 100;
  std::vector<double> ms, rss_frame, rss_kib;  // time per frame; RSS samples after warm-up
  int counts[5] = {}, lost_on_faults = 0, fault_frames = 0;
  double max_translation = 0.0;
  bool all_finite = true;

  void add(int i, Fault fault, const acvo::OdometryResult& r, double frame_ms) {
    ms.push_back(frame_ms);
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

  // rss_start and rss_end are taken between frames, the samples with a frame's images alive.
  void print(int frames, long rss_start, long rss_end) const {
    std::printf("\nframes processed: %d (%d carried a fault)\n", frames, fault_frames);
    std::printf(
        "tracking: ok %d, hard %d, lost %d (%d of them on fault frames), first %d, bad %d\n",
        counts[int(acvo::Tracking::kOk)], counts[int(acvo::Tracking::kHard)],
        counts[int(acvo::Tracking::kLost)], lost_on_faults,
        counts[int(acvo::Tracking::kFirstFrame)], counts[int(acvo::Tracking::kBadFrame)]);
    std::printf("RSS: %ld KiB before the first frame, %ld KiB after the last\n", rss_start,
                rss_end);
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
  }
};

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
  Tally tally;
  tally.ms.reserve(std::size_t(args.frames));
  const long rss_start = acvo::tools::residentKiB();
  double previous_stamp = 0.0;
  for (int i = 0; i < args.frames; ++i) {
    const Fault fault = faultAt(i, args.fault_every, blackout_frames);
    const acvo::Frame frame = inject(sequence.frame(i).toFrame(), fault, previous_stamp);
    previous_stamp = frame.stamp;
    const auto t0 = std::chrono::steady_clock::now();
    const acvo::OdometryResult r = odometry.process(frame);
    tally.add(
        i, fault, r,
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  tally.print(args.frames, rss_start, acvo::tools::residentKiB());
  return tally.all_finite ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kDescription, "acvo_soak"};
  Arguments args;
  if (const auto status = parseArguments(app, args, argc, argv)) return *status;
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::cerr << "acvo_soak: " << e.what() << "\n";
    return 1;
  }
}
