// acvo_tum: runs acvo's odometry over a TUM-format dataset folder and writes the trajectory.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "acvo/cloud/colour_depth_check.hpp"
#include "acvo/dataset/tum.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/params.hpp"
#include "tool_support.hpp"

namespace {

constexpr const char* kDescription =
    R"(Runs acvo's odometry over a TUM RGB-D folder (rgb.txt, depth.txt, optional
associations.txt, groundtruth.txt, camera.yaml) and writes the trajectory in TUM format
(default DATASET_DIR/acvo_trajectory.txt). Each frame is registered to the current keyframe
(--set odometry.reference=previous_frame: to the frame before; --config config/paper.yaml:
the paper's A-CVO). The first pose is the ground-truth pose of the first frame when
groundtruth.txt exists, identity otherwise.
)";

constexpr const char* kFooter =
    "--set overrides one parameter of the config, e.g. --set coarse_to_fine.color_ell=0.2.\n"
    "Last line: frames=N median_ms=X p90_ms=Y failures=Z (cloud + registration per frame).\n"
    "Exit status: 0 success, 2 bad arguments or input.";

struct Options {
  std::string dataset, config, camera, output, stats;
  std::vector<std::string> sets;
  long start = 0, frames = -1;
  int threads = -1;
};

// The command line into `o`; nullopt to go on, else the exit status.
std::optional<int> parseOptions(CLI::App& app, Options& o, int argc, char** argv) {
  using acvo::tools::numberIn;
  const long kLongMax = std::numeric_limits<long>::max();
  acvo::tools::setUpCommandLine(app, kFooter);
  app.add_option("DATASET_DIR", o.dataset, "the TUM RGB-D folder")->type_name("")->required();
  app.add_option("--config", o.config, "parameters (YAML; default: the built-in defaults)")
      ->type_name("FILE");
  app.add_option("--camera", o.camera,
                 "intrinsics, and a lens distortion the frames are undistorted by (default: "
                 "DATASET_DIR/camera.yaml, else default)")
      ->type_name("FILE|fr1|fr2|fr3|default");
  app.add_option("--output", o.output, "the trajectory (default DATASET_DIR/acvo_trajectory.txt)")
      ->type_name("TRAJ");
  app.add_option("--stats", o.stats, "per-frame figures as CSV")->type_name("CSV");
  app.add_option("--start", o.start, "first frame (0-based)")
      ->type_name("N")
      ->capture_default_str()
      ->transform(numberIn(0L, kLongMax, "a non-negative integer"));
  app.add_option("--frames", o.frames, "number of frames (default: to the end)")
      ->type_name("N")
      ->transform(numberIn(0L, kLongMax, "a non-negative integer"));
  app.add_option("--threads", o.threads, "worker threads (default: the config's)")
      ->type_name("N")
      ->transform(numberIn(0, std::numeric_limits<int>::max(), "a non-negative integer"));
  app.add_option("--set", o.sets, "override one parameter of the config (repeatable)")
      ->type_name("SECTION.KEY=VALUE")
      ->allow_extra_args(false);
  return acvo::tools::parseCommandLine(app, argc, argv);
}

// What the intrinsics and lens of the folder are, on stderr: a calibration the user should know
// is missing or taken from elsewhere.
void noteCamera(const acvo::TumDataset& data) {
  const acvo::Camera& c = data.camera();
  if (data.distortion().any()) {
    const auto& k = data.distortion().coefficients;
    std::cerr << "acvo_tum: the camera's lens distortion (k1 k2 p1 p2 k3 = " << k[0] << ' ' << k[1]
              << ' ' << k[2] << ' ' << k[3] << ' ' << k[4]
              << "): every frame undistorted on loading\n";
  }
  if (acvo::nominalIntrinsics(c, data.distortion())) {
    std::cerr << "acvo_tum: note: the intrinsics (fx " << c.fx << ", fy " << c.fy << ", cx " << c.cx
              << ", cy " << c.cy << ") are nominal, not a calibration: exact for a "
              << "rendered camera; a real one's may be a few percent off, and acvo's translation "
              << "carries that in full (--camera FILE gives a calibration; fr1, fr2 or fr3, "
              << "TUM's)\n";
  }
  if (!data.namedCamera().empty()) {
    std::cerr << "acvo_tum: note: no camera.yaml; the folder's name (" << data.namedCamera()
              << ") gives TUM's calibrated intrinsics (fx " << c.fx << ", fy " << c.fy << ", cx "
              << c.cx << ", cy " << c.cy << ")" << (data.distortion().any() ? " and lens" : "")
              << " (--camera default or a camera file for others)\n";
  }
  if (c.mirrored()) {
    std::cerr << "acvo_tum: note: a negative focal length (fx " << c.fx << ", fy " << c.fy
              << "): that image axis runs against the optical frame's, as in ICL-NUIM's "
              << "intrinsics (fy -480); pixels are back-projected with the signs given, and the "
              << "trajectory is in the optical frame they define\n";
  }
}

// --stats: one CSV line per frame; the last columns are the engine's own figures
// (acvo::engineFigures), named for the engine in use.
class StatsWriter {
 public:
  StatsWriter(const std::string& path, acvo::Engine engine) {
    if (path.empty()) return;
    out_.open(path);
    if (!out_) throw std::runtime_error("cannot write " + path);
    figures_ = engine == acvo::Engine::kPaper
                   ? std::vector<std::string>{"ell_at_bound", "ell_max_reductions", "inner_product"}
                   : std::vector<std::string>{"brightness_gain", "vignetting", "dense_weight"};
    out_ << "frame,stamp,tracking,status,points,fixed_points,iterations,ell,nnz,matched_fraction,"
            "ms_selection,ms_labels,ms_prepare,ms_cloud,ms_neighbours,ms_registration,ms_frame,"
            "rss_kib,keyframe,new_keyframe,depth_delay_ms,depth_moved,second_start,ms_window,"
            "ms_window_wait,window_links,window_shift_mm,window_shift_deg";
    for (const auto& name : figures_) out_ << ',' << name;
    out_ << '\n';
  }
  void write(long k, const std::string& stamp, const acvo::OdometryResult& r) {
    if (!out_.is_open()) return;
    const acvo::SolverResult& s = r.solver;
    out_ << k << ',' << stamp << ',' << acvo::toString(r.tracking) << ','
         << acvo::toString(s.status) << ',' << r.moving_points << ',' << r.fixed_points << ','
         << s.iterations << ',' << s.ell << ',' << s.nnz << ',' << s.matched_fraction << ','
         << r.cloud_stats.ms_selection << ',' << r.cloud_stats.ms_labels << ',' << r.ms_prepare
         << ',' << r.ms_cloud << ',' << s.ms_neighbours << ',' << r.ms_registration << ','
         << r.ms_cloud + r.ms_registration + r.ms_window_wait << ',' << acvo::tools::residentKiB()
         << ',' << r.keyframe_index << ',' << int(r.new_keyframe) << ',' << 1e3 * r.depth_delay
         << ',' << (r.depth_retimed ? 2 : int(r.depth_synced)) << ','
         << (r.second_start_kept ? 2 : int(r.second_start)) << ',' << r.ms_window << ','
         << r.ms_window_wait << ',' << r.window_links << ',' << 1e3 * r.window_shift << ','
         << r.window_shift_deg;
    const auto figures = acvo::engineFigures(s);
    for (const auto& name : figures_) {
      const auto it = std::find_if(figures.begin(), figures.end(),
                                   [&](const auto& f) { return f.first == name; });
      out_ << ',' << (it == figures.end() ? std::nan("") : it->second);
    }
    out_ << '\n';
  }

 private:
  std::ofstream out_;
  std::vector<std::string> figures_;
};

// The odometry's result for frame k, with what it says on stderr: the colour check's verdict,
// and why a frame was lost or bad. nullopt when the frame could not be loaded.
std::optional<acvo::OdometryResult> processFrame(acvo::Odometry& odometry,
                                                 const acvo::TumDataset& data, long k,
                                                 bool progress) {
  acvo::OdometryResult r;
  try {
    r = odometry.process(data.loadFrame(std::size_t(k)));
  } catch (const std::exception& e) {
    std::cerr << "\nacvo_tum: frame " << k << " skipped: " << e.what() << "\n";
    return std::nullopt;
  }
  const char* line = progress ? "\n" : "";
  if (r.colour_verdict_now) {
    const bool unregistered =
        odometry.colourCheck().verdict().state == acvo::ColourDepthCheck::State::kUnregistered;
    std::cerr << line << "acvo_tum: " << (unregistered ? "warning: " : "")
              << odometry.describeColour() << "\n";
  }
  if (r.tracking == acvo::Tracking::kLost || r.tracking == acvo::Tracking::kBadFrame) {
    std::cerr << line << "acvo_tum: frame " << k << " ("
              << data.frames()[std::size_t(k)].rgb.stamp_text << "): " << acvo::toString(r.tracking)
              << ": " << r.message << "\n";
  }
  return r;
}

// The frames first to last through the odometry: the trajectory, each frame's time (the first
// frame's left out) and the frames lost or rejected.
struct Run {
  acvo::Trajectory trajectory;
  std::vector<double> frame_ms;
  long failures = 0;
};

Run runFrames(acvo::Odometry& odometry, const acvo::TumDataset& data, long first, long last,
              StatsWriter& stats) {
  const bool progress = isatty(STDERR_FILENO);
  Run run;
  for (long k = first; k < last; ++k) {
    const auto& entry = data.frames()[std::size_t(k)];
    const std::optional<acvo::OdometryResult> r = processFrame(odometry, data, k, progress);
    run.failures +=
        !r || r->tracking == acvo::Tracking::kLost || r->tracking == acvo::Tracking::kBadFrame;
    if (!r) continue;
    if (r->tracking != acvo::Tracking::kBadFrame) {
      run.trajectory.push_back({entry.rgb.stamp_text, entry.rgb.stamp, r->pose});
    }
    const double ms = r->ms_cloud + r->ms_registration + r->ms_window_wait;
    if (r->tracking != acvo::Tracking::kFirstFrame) run.frame_ms.push_back(ms);
    stats.write(k, entry.rgb.stamp_text, *r);
    if (progress) {
      std::fprintf(stderr, "\racvo_tum: frame %ld/%ld  %3d it  %6.1f ms  %s    ", k - first + 1,
                   last - first, r->solver.iterations, ms, acvo::toString(r->tracking).c_str());
    }
  }
  if (progress) std::fprintf(stderr, "\n");
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kDescription, "acvo_tum"};
  Options opt;
  if (const auto status = parseOptions(app, opt, argc, argv)) return *status;
  try {
    acvo::Params params;
    try {
      params = acvo::tools::loadToolParams(opt.config, opt.sets);
    } catch (const std::exception& e) {  // a malformed --set, an unknown key, a bad config
      return acvo::tools::usageError(app, e.what());
    }
    if (opt.threads >= 0) params.odometry.threads = opt.threads;
    const acvo::TumDataset data(opt.dataset, opt.camera);
    noteCamera(data);
    const std::string output =
        opt.output.empty() ? opt.dataset + "/acvo_trajectory.txt" : opt.output;
    const long first = std::min<long>(opt.start, long(data.size()));
    const long last =
        opt.frames < 0 ? long(data.size()) : std::min<long>(long(data.size()), first + opt.frames);
    if (first >= last) {
      return acvo::tools::usageError(
          app, "no frames to process (dataset has " + std::to_string(data.size()) + ")");
    }
    StatsWriter stats(opt.stats, params.registration.engine);
    acvo::Odometry odometry(params);
    if (data.groundtruth()) {
      const double stamp = data.frames()[std::size_t(first)].rgb.stamp;
      if (const auto* p = acvo::tools::nearestPose(*data.groundtruth(), stamp)) {
        odometry.reset(p->pose);
      }
    }
    const Run run = runFrames(odometry, data, first, last, stats);
    acvo::writeTrajectory(output, run.trajectory, "acvo trajectory of " + opt.dataset);
    std::printf("wrote %zu poses to %s\n", run.trajectory.size(), output.c_str());
    std::printf("frames=%zu median_ms=%.3f p90_ms=%.3f failures=%ld\n", run.trajectory.size(),
                acvo::tools::percentile(run.frame_ms, 0.5),
                acvo::tools::percentile(run.frame_ms, 0.9), run.failures);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "acvo_tum: " << e.what() << "\n";
    return 2;
  }
}
