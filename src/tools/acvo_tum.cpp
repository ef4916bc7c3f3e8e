// acvo_tum: runs A-CVO odometry over a TUM-format dataset folder and writes the trajectory.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "acvo/odometry.hpp"
#include "acvo/params.hpp"
#include "acvo/tum.hpp"
#include "tool_support.hpp"

namespace {

const char* kUsage =
    "usage: acvo_tum DATASET_DIR [--config FILE] [--camera FILE|fr1|fr2|fr3|default]\n"
    "                [--output TRAJ] [--stats CSV] [--start N] [--frames N] [--threads N]\n"
    "                [--set SECTION.KEY=VALUE ...]\n"
    "Runs A-CVO frame-to-frame odometry over a TUM RGB-D folder (rgb.txt, depth.txt,\n"
    "optional associations.txt, groundtruth.txt, camera.yaml) and writes the trajectory in\n"
    "TUM format (default DATASET_DIR/acvo_trajectory.txt). The first pose is the ground-truth\n"
    "pose of the first frame when groundtruth.txt exists, identity otherwise.\n"
    "--set overrides one parameter of the config, e.g. --set solver.ell_policy=fixed_schedule.\n"
    "Last line: frames=N median_ms=X p90_ms=Y failures=Z (cloud + registration per frame).\n";

struct Options {
  std::string dataset, config, camera, output, stats;
  std::vector<std::string> sets;
  long start = 0, frames = -1;
  int threads = -1;
};

[[noreturn]] void usageError(const std::string& why) {
  std::cerr << "acvo_tum: " << why << "\n" << kUsage;
  std::exit(2);
}

long parseLong(const std::string& flag, const std::string& value) {
  try {
    std::size_t used = 0;
    const long v = std::stol(value, &used);
    if (used == value.size() && v >= 0) return v;
  } catch (const std::exception&) {
  }
  usageError(flag + " expects a non-negative integer, got '" + value + "'");
}

Options parseOptions(int argc, char** argv) {
  Options o;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    auto value = [&]() -> std::string {
      if (k + 1 >= argc) usageError(a + " needs a value");
      return argv[++k];
    };
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (a == "--config") {
      o.config = value();
    } else if (a == "--camera") {
      o.camera = value();
    } else if (a == "--output") {
      o.output = value();
    } else if (a == "--stats") {
      o.stats = value();
    } else if (a == "--start") {
      o.start = parseLong(a, value());
    } else if (a == "--frames") {
      o.frames = parseLong(a, value());
    } else if (a == "--threads") {
      o.threads = int(parseLong(a, value()));
    } else if (a == "--set") {
      o.sets.push_back(value());
    } else if (!a.empty() && a[0] == '-') {
      usageError("unknown option " + a);
    } else if (o.dataset.empty()) {
      o.dataset = a;
    } else {
      usageError("unexpected argument " + a);
    }
  }
  if (o.dataset.empty()) usageError("missing DATASET_DIR");
  return o;
}

acvo::Params loadParameters(const Options& o) {
  acvo::Params p;
  try {
    p = acvo::tools::loadToolParams(o.config, o.sets);
  } catch (const std::invalid_argument& e) {
    usageError(e.what());
  }
  if (o.threads >= 0) p.odometry.threads = o.threads;
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parseOptions(argc, argv);
  try {
    const acvo::Params params = loadParameters(opt);
    const acvo::TumDataset data(opt.dataset, opt.camera);
    const std::string output =
        opt.output.empty() ? opt.dataset + "/acvo_trajectory.txt" : opt.output;
    const long first = std::min<long>(opt.start, long(data.size()));
    const long last =
        opt.frames < 0 ? long(data.size()) : std::min<long>(long(data.size()), first + opt.frames);
    if (first >= last)
      usageError("no frames to process (dataset has " + std::to_string(data.size()) + ")");

    std::ofstream stats;
    if (!opt.stats.empty()) {
      stats.open(opt.stats);
      if (!stats) throw std::runtime_error("cannot write " + opt.stats);
      stats << "frame,stamp,tracking,status,points,fixed_points,iterations,ell,ell_at_bound,nnz,"
               "inner_product,matched_fraction,ms_selection,ms_labels,ms_prepare,ms_cloud,ms_"
               "neighbours,ms_step,ms_ell,"
               "ms_registration,ms_frame,rss_kib,keyframe,new_keyframe\n";
    }

    acvo::Odometry odometry(params);
    Eigen::Isometry3d world_from_first = Eigen::Isometry3d::Identity();
    if (data.groundtruth()) {
      const double stamp = data.frames()[std::size_t(first)].rgb.stamp;
      if (const auto* p = acvo::tools::nearestPose(*data.groundtruth(), stamp)) {
        world_from_first = p->pose;
      }
    }
    odometry.reset(world_from_first);

    const bool progress = isatty(STDERR_FILENO);
    acvo::Trajectory trajectory;
    std::vector<double> frame_ms;
    long failures = 0;
    for (long k = first; k < last; ++k) {
      const auto& entry = data.frames()[std::size_t(k)];
      acvo::OdometryResult r;
      try {
        r = odometry.process(data.loadFrame(std::size_t(k)));
      } catch (const std::exception& e) {
        std::cerr << "\nacvo_tum: frame " << k << " skipped: " << e.what() << "\n";
        ++failures;
        continue;
      }
      const bool failed =
          r.tracking == acvo::Tracking::kLost || r.tracking == acvo::Tracking::kBadFrame;
      if (failed) {
        ++failures;
        std::cerr << (progress ? "\n" : "") << "acvo_tum: frame " << k << " ("
                  << entry.rgb.stamp_text << "): " << acvo::toString(r.tracking) << ": "
                  << r.message << "\n";
      }
      if (r.tracking != acvo::Tracking::kBadFrame) {
        trajectory.push_back({entry.rgb.stamp_text, entry.rgb.stamp, r.pose});
      }
      const double ms = r.ms_cloud + r.ms_registration;
      if (r.tracking != acvo::Tracking::kFirstFrame) frame_ms.push_back(ms);
      if (stats.is_open()) {
        const auto& s = r.solver;
        stats << k << ',' << entry.rgb.stamp_text << ',' << acvo::toString(r.tracking) << ','
              << acvo::toString(s.status) << ',' << r.moving_points << ',' << r.fixed_points << ','
              << s.iterations << ',' << s.ell << ',' << int(s.ell_at_bound) << ',' << s.nnz << ','
              << s.inner_product << ',' << s.matched_fraction << ',' << r.cloud_stats.ms_selection
              << ',' << r.cloud_stats.ms_labels << ',' << r.ms_prepare << ',' << r.ms_cloud << ','
              << s.ms_neighbours << ',' << s.ms_step << ',' << s.ms_ell << ',' << r.ms_registration
              << ',' << ms << ',' << acvo::tools::residentKiB() << ',' << r.keyframe_index << ','
              << int(r.new_keyframe) << '\n';
      }
      if (progress) {
        std::fprintf(stderr, "\racvo_tum: frame %ld/%ld  %3d it  %6.1f ms  %s    ", k - first + 1,
                     last - first, r.solver.iterations, ms, acvo::toString(r.tracking).c_str());
      }
    }
    if (progress) std::fprintf(stderr, "\n");
    acvo::writeTrajectory(output, trajectory, "acvo trajectory of " + opt.dataset);
    std::printf("wrote %zu poses to %s\n", trajectory.size(), output.c_str());
    std::printf("frames=%zu median_ms=%.3f p90_ms=%.3f failures=%ld\n", trajectory.size(),
                acvo::tools::percentile(frame_ms, 0.5), acvo::tools::percentile(frame_ms, 0.9),
                failures);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "acvo_tum: " << e.what() << "\n";
    return 2;
  }
}
