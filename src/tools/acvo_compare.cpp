// acvo_compare: acvo against OpenCV contrib's RGB-D odometries (RgbdOdometry, ICPOdometry,
// RgbdICPOdometry) on TUM-format folders: RPE over 1 s, ATE, lost frames and time per frame, as
// one table (and JSON).
//
// Fair by construction: the peers run as OpenCV's own TUM sample runs them (peers.hpp: NaN holes,
// compute(current, previous)) at every maximum depth given, with and without the last motion as
// their initial guess, the best setting named; acvo
// runs on as many threads as asked (one by default: the peers are serial) and its CPU time is
// shown; every frame goes to every method in turn (the order rotating), so that a machine that
// slows down or speeds up during the run does so for all of them; --repeat gives the median of
// the per-run medians and their spread.
#include <ctime>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "acvo/dataset/evaluation.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/params.hpp"
#include "acvo/dataset/tum.hpp"
#include "peers.hpp"
#include "tool_support.hpp"

namespace {

constexpr const char* kDescription =
    R"(Runs acvo and OpenCV contrib's RgbdOdometry, ICPOdometry and RgbdICPOdometry over TUM RGB-D
folders (rgb.txt, depth.txt, associations.txt, groundtruth.txt, camera.yaml) and prints one
table: RPE over 1 s (translation m/s, rotation deg/s), ATE (m), lost frames, median time per
frame (wall and CPU) and the median time as a ratio of the best RgbdOdometry setting's.
The OpenCV odometries run as OpenCV's TUM sample runs them (missing depth as NaN, the current
frame registered to the previous one), once per --peer-max-depth and --peer-guess (none, as the
sample; last, the last frame's motion as the initial guess, which helps them on fast turns); the
<peer>_best row repeats the setting with the lowest errors (translation and rotation, each
relative to the settings' mean). Every method sees the same decoded frames, frame by frame in
turn; times cover the odometry call only (acvo: cloud building and registration; OpenCV: grey
conversion, hole marking, pyramids and registration).
--stride K keeps every K-th frame: the same camera moving K times faster between frames, the
way to see how wide each method's basin is (the dataset is then named <folder>_everyK).
--camera gives every method other intrinsics than the folder's camera.yaml: a calibration of
one's own, or a focal length a few percent off to see how much each method depends on it.
--offset auto evaluates each dataset at the offset between the reference's clock and the
frames' stamps at which every row's frame-to-frame turns agree best with the reference's
(found from all rows together, so that no method is favoured), printed below the table; a
camera's stamps that lag its exposures by some milliseconds charge every method with the
reference's motion over that lag, and a precise method the most in proportion.
)";

constexpr const char* kFooter = "Exit status: 0 success, 2 bad arguments or input.";

struct Options {
  std::vector<std::string> datasets, methods{"acvo", "rgbd", "icp", "rgbd_icp"}, sets;
  std::vector<double> peer_max_depth{4.0, 10.0};
  std::vector<int> threads{1};
  std::string config, label = "acvo", json, trajectories, camera;
  long frames = -1, stride = 1;
  int repeat = 1;
  std::vector<std::string> peer_guess{"none", "last"};
  std::optional<double> offset = 0.0;  // empty: estimated per dataset (--offset auto)
};

// The command line into `o`; nullopt to go on, else the exit status.
std::optional<int> parseOptions(CLI::App& app, Options& o, int argc, char** argv) {
  acvo::tools::setUpCommandLine(app, kFooter);
  app.add_option("DATASET_DIR", o.datasets, "TUM RGB-D folders")->type_name("")->required();
  app.add_option("--methods", o.methods, "comma-separated subset of acvo,rgbd,icp,rgbd_icp")
      ->type_name("LIST")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->default_str("all")
      ->check(CLI::IsMember({"acvo", "rgbd", "icp", "rgbd_icp"}).description(""));
  app.add_option("--peer-max-depth", o.peer_max_depth,
                 "the OpenCV odometries' maximum depth (m), one row per value")
      ->type_name("LIST")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->default_str("4,10")
      ->check(acvo::tools::numberIn(1e-3, 1e3, "within [0.001, 1000]"));
  app.add_option("--threads", o.threads,
                 "acvo's worker threads, one row per value (0 = every core); 1 by default, as "
                 "the OpenCV odometries are serial")
      ->type_name("LIST")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->default_str("1")
      ->check(acvo::tools::numberIn(0, 1024, "within [0, 1024]"));
  app.add_option("--repeat", o.repeat,
                 "run everything N times: times are the median of the runs' medians")
      ->type_name("N")
      ->capture_default_str()
      ->check(acvo::tools::numberIn(1, 1000, "within [1, 1000]"));
  app.add_option("--peer-guess", o.peer_guess,
                 "the OpenCV odometries' initial guess, one row per value: none (as OpenCV's "
                 "sample) or last (the last frame's motion)")
      ->type_name("LIST")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->default_str("none,last")
      ->check(CLI::IsMember({"none", "last"}).description(""));
  app.add_option("--camera", o.camera,
                 "every method's intrinsics, and a lens distortion the frames are undistorted by "
                 "(default: each DATASET_DIR/camera.yaml, else default)")
      ->type_name("FILE|fr1|fr2|fr3|default");
  app.add_option("--config", o.config, "acvo parameters (default: built in, as config/acvo.yaml)")
      ->type_name("FILE");
  app.add_option("--set", o.sets, "override one acvo parameter (repeatable)")
      ->type_name("SECTION.KEY=VALUE")
      ->allow_extra_args(false);
  app.add_option("--label", o.label, "name of the acvo row")
      ->type_name("NAME")
      ->capture_default_str();
  app.add_option("--frames", o.frames, "use the first N frames of each dataset")
      ->type_name("N")
      ->check(
          acvo::tools::numberIn(0L, std::numeric_limits<long>::max(), "a non-negative integer"));
  app.add_option("--stride", o.stride,
                 "use every K-th frame (a camera K times faster); --frames counts the frames used")
      ->type_name("K")
      ->capture_default_str()
      ->check(acvo::tools::numberIn(1L, 1000000L, "within [1, 1000000]"));
  acvo::tools::addOffsetOption(app, o.offset,
                               "added to the frames' stamps where they are looked up in the "
                               "reference (a clock offset; auto: found per dataset)");
  app.add_option("--json", o.json, "write every figure as JSON")->type_name("FILE");
  app.add_option("--trajectories", o.trajectories,
                 "write each estimate as DIR/<dataset>-<method>[-<setting>].txt")
      ->type_name("DIR");
  if (const auto status = acvo::tools::parseCommandLine(app, argc, argv)) return status;
  // --methods "" or ",": CLI11 leaves the list empty.
  if (o.methods.empty()) return acvo::tools::usageError(app, "--methods is empty");
  if (o.peer_max_depth.empty()) return acvo::tools::usageError(app, "--peer-max-depth is empty");
  if (o.peer_guess.empty()) return acvo::tools::usageError(app, "--peer-guess is empty");
  if (o.threads.empty()) return acvo::tools::usageError(app, "--threads is empty");
  return std::nullopt;
}

// One row of the table: a method at one setting over one dataset.
struct Row {
  std::string dataset, method, setting;
  bool best = false;  // a <peer>_best row
  acvo::Trajectory trajectory;
  long lost = 0;
  double offset = 0.0;  // s, added to the stamps against the reference's
  bool offset_found = false;    // by --offset auto
  std::string offset_refused;   // why --offset auto found none (then offset 0)
  double rpe_trans = NAN, rpe_rot = NAN, ate = NAN;
  // Per run: the median and 90th percentile over frames of the wall and CPU times (ms), and
  // the median as a ratio of the best RgbdOdometry row's median in that run.
  std::vector<double> median_ms, p90_ms, cpu_median_ms, ratio;
};

Row makeRow(const std::string& dataset, const std::string& method, const std::string& setting) {
  Row row;
  row.dataset = dataset;
  row.method = method;
  row.setting = setting;
  return row;
}

// A method that registers frames one after the other: process() returns false when the frame
// is lost; pose() is the camera pose after it.
class Method {
 public:
  virtual ~Method() = default;
  virtual bool process(const acvo::Frame& frame) = 0;
  virtual const Eigen::Isometry3d& pose() const = 0;
  // Its poses are the depth camera's, at the depth images' stamps (a method of depth alone);
  // otherwise at the colour images' (the stamps acvo's poses carry).
  virtual bool depthOnly() const { return false; }
};

class AcvoMethod : public Method {
 public:
  AcvoMethod(const acvo::Params& params, const Eigen::Isometry3d& start) : odometry_(params) {
    odometry_.reset(start);
  }
  bool process(const acvo::Frame& frame) override {
    const acvo::OdometryResult r = odometry_.process(frame);
    return r.tracking != acvo::Tracking::kLost && r.tracking != acvo::Tracking::kBadFrame;
  }
  const Eigen::Isometry3d& pose() const override { return odometry_.pose(); }

 private:
  acvo::Odometry odometry_;
};

class PeerMethod : public Method {
 public:
  PeerMethod(const acvo::peers::PeerSetup& setup, const acvo::Camera& camera,
             const Eigen::Isometry3d& start)
      : peer_(setup, camera, start), depth_only_(setup.kind == acvo::peers::PeerKind::kIcp) {}
  bool process(const acvo::Frame& frame) override { return peer_.process(frame); }
  const Eigen::Isometry3d& pose() const override { return peer_.pose(); }
  bool depthOnly() const override { return depth_only_; }

 private:
  acvo::peers::PeerOdometry peer_;
  bool depth_only_;
};

// What one row runs: its row and how to make a fresh method for each run.
struct Entry {
  Row row;
  std::function<std::unique_ptr<Method>()> make;
};

// The first pose: the ground truth nearest the first frame, identity without one.
Eigen::Isometry3d startPose(const acvo::TumDataset& data, double stamp) {
  const acvo::StampedPose* p =
      data.groundtruth() ? acvo::tools::nearestPose(*data.groundtruth(), stamp) : nullptr;
  return p ? p->pose : Eigen::Isometry3d::Identity();
}

std::string baseName(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string threadsSetting(int threads) {
  if (threads == 0) return "all_cores";
  return std::to_string(threads) + (threads == 1 ? "_thread" : "_threads");
}

// "4m", "10m_guess": the maximum depth, and whether the last motion is the initial guess.
std::string peerSetting(double max_depth, bool guess) {
  std::ostringstream s;
  s << max_depth << "m" << (guess ? "_guess" : "");
  return s.str();
}

// The rows of one dataset: acvo once per thread count, each peer once per maximum depth and
// initial guess.
std::vector<Entry> entriesFor(const Options& opt, const acvo::Params& params,
                              const acvo::TumDataset& data, const std::string& dataset,
                              const Eigen::Isometry3d& start) {
  std::vector<Entry> entries;
  for (const auto& method : opt.methods) {
    if (method == "acvo") {
      for (int threads : opt.threads) {
        acvo::Params p = params;
        p.odometry.threads = threads;
        entries.push_back({makeRow(dataset, opt.label, threadsSetting(threads)),
                           [p, start] { return std::make_unique<AcvoMethod>(p, start); }});
      }
      continue;
    }
    for (double max_depth : opt.peer_max_depth) {
      for (const std::string& guess : opt.peer_guess) {
        acvo::peers::PeerSetup setup;
        setup.kind = acvo::peers::parsePeerKind(method);
        setup.max_depth = max_depth;
        setup.previous_motion_guess = guess == "last";
        const acvo::Camera camera = data.camera();
        entries.push_back({makeRow(dataset, method, peerSetting(max_depth, guess == "last")),
                           [setup, camera, start] {
                             return std::make_unique<PeerMethod>(setup, camera, start);
                           }});
      }
    }
  }
  return entries;
}

double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

// One run over the frames: every frame to every method in turn, the first method of each frame
// rotating. The first run also records the trajectories.
void runOnce(std::vector<Entry>& entries, const std::vector<acvo::Frame>& frames,
             const std::vector<std::size_t>& index, const acvo::TumDataset& data, bool record) {
  const std::size_t m = entries.size();
  std::vector<std::unique_ptr<Method>> methods;
  for (auto& e : entries) methods.push_back(e.make());
  std::vector<std::vector<double>> wall(m), cpu(m);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t j = (i + k) % m;
      const double cpu0 = processCpuMs();
      const auto t0 = std::chrono::steady_clock::now();
      const bool ok = methods[j]->process(frames[i]);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const double cpu_ms = processCpuMs() - cpu0;
      if (i > 0) {  // the first frame only starts the sequence
        wall[j].push_back(ms);
        cpu[j].push_back(cpu_ms);
      }
      if (!record) continue;
      Row& row = entries[j].row;
      if (!ok && i > 0) ++row.lost;
      const auto& frame = data.frames()[index[i]];
      const auto& stamp = methods[j]->depthOnly() ? frame.depth : frame.rgb;
      row.trajectory.push_back({stamp.stamp_text, stamp.stamp, methods[j]->pose()});
    }
  }
  for (std::size_t j = 0; j < m; ++j) {
    Row& row = entries[j].row;
    row.median_ms.push_back(acvo::tools::percentile(wall[j], 0.5));
    row.p90_ms.push_back(acvo::tools::percentile(wall[j], 0.9));
    row.cpu_median_ms.push_back(acvo::tools::percentile(cpu[j], 0.5));
  }
}

void evaluate(Row& row, const acvo::TumDataset& data, double offset) {
  row.offset = offset;
  if (!data.groundtruth()) return;
  try {
    const acvo::Trajectory& gt = *data.groundtruth();
    const acvo::RpeResult rpe =
        acvo::computeRpe(gt, row.trajectory, 1.0, acvo::DeltaUnit::kSeconds, offset);
    row.rpe_trans = rpe.trans.rmse;
    row.rpe_rot = rpe.rot_deg.rmse;
    row.ate = acvo::computeAte(gt, row.trajectory, 0.02, offset).trans.rmse;
  } catch (const std::exception& e) {
    std::cerr << "acvo_compare: " << row.dataset << " " << row.method << " " << row.setting
              << ": no evaluation: " << e.what() << "\n";
  }
}

// Per OpenCV odometry, the index of its best row: the fewest lost frames, then the lowest sum
// of the translation and rotation errors, each divided by its mean over the settings.
std::map<std::string, std::size_t> bestRows(const std::vector<Entry>& entries,
                                            const std::string& acvo_label) {
  std::map<std::string, std::vector<std::size_t>> by_method;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    if (entries[k].row.method != acvo_label) by_method[entries[k].row.method].push_back(k);
  }
  std::map<std::string, std::size_t> best;
  for (const auto& [method, rows] : by_method) {
    double mean_t = 0.0, mean_r = 0.0;
    for (std::size_t k : rows) {
      mean_t += entries[k].row.rpe_trans / double(rows.size());
      mean_r += entries[k].row.rpe_rot / double(rows.size());
    }
    const auto worse = [&](std::size_t a, std::size_t b) {  // a is worse than b
      const Row &ra = entries[a].row, &rb = entries[b].row;
      if (ra.lost != rb.lost) return ra.lost > rb.lost;
      const double sa = ra.rpe_trans / mean_t + ra.rpe_rot / mean_r;
      const double sb = rb.rpe_trans / mean_t + rb.rpe_rot / mean_r;
      return !(sa <= sb) && std::isfinite(sb);  // NaN (no ground truth) is never better
    };
    std::size_t chosen = rows.front();
    for (std::size_t k : rows) {
      if (worse(chosen, k)) chosen = k;
    }
    best[method] = chosen;
  }
  return best;
}

std::string milliseconds(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%+.1f ms", 1e3 * seconds);
  return buf;
}

double median(std::vector<double> v) { return acvo::tools::percentile(std::move(v), 0.5); }

// (max - min) / median of the runs' values, in percent; 0 for a single run.
double spreadPercent(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double m = median(v);
  return m > 0.0 ? 100.0 * (*hi - *lo) / m : NAN;
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string jsonList(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + jsonNumber(v[k]);
  return s + "]";
}

void printTable(const std::vector<Row>& rows, const Options& opt) {
  std::string threads;
  for (int t : opt.threads) threads += (threads.empty() ? "" : ",") + threadsSetting(t);
  const std::string camera = opt.camera.empty() ? "" : "; camera: " + opt.camera;
  const std::string offset =
      opt.offset && *opt.offset != 0.0
          ? "; the frames' stamps " + milliseconds(*opt.offset) + " against the reference's"
          : "";
  std::printf("# acvo on %s; OpenCV odometries serial, as OpenCV's TUM sample runs them (NaN "
              "holes; _guess: the last motion as initial guess); times: median over frames, median of %d run%s interleaved "
              "frame by frame; vs_rgbd: median time / the best RgbdOdometry setting's, per "
              "run%s%s\n",
              threads.c_str(), opt.repeat, opt.repeat == 1 ? "" : "s", camera.c_str(),
              offset.c_str());
  std::printf("%-20s %-12s %-12s %10s %11s %8s %5s %9s %8s %8s %8s\n", "dataset", "method",
              "setting", "rpe_t_m/s", "rpe_r_deg/s", "ate_m", "lost", "median_ms", "cpu_ms",
              "spread_%", "vs_rgbd");
  for (const auto& r : rows) {
    std::printf("%-20s %-12s %-12s %10.4f %11.3f %8.4f %5ld %9.2f %8.2f %8.1f %8.2f\n",
                r.dataset.c_str(), r.method.c_str(), r.setting.c_str(), r.rpe_trans, r.rpe_rot,
                r.ate, r.lost, median(r.median_ms), median(r.cpu_median_ms),
                spreadPercent(r.median_ms), median(r.ratio));
  }
}

void writeJson(const std::vector<Row>& rows, const Options& opt) {
  std::ofstream out(opt.json);
  if (!out) throw std::runtime_error("cannot write " + opt.json);
  out << "{\"rpe_delta_s\": 1, \"repeat\": " << opt.repeat;
  if (!opt.camera.empty()) out << ", \"camera\": " << acvo::tools::jsonString(opt.camera);
  out << ", \"acvo_threads\": [";
  for (std::size_t k = 0; k < opt.threads.size(); ++k) out << (k ? ", " : "") << opt.threads[k];
  out << "], \"runs\": [";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Row& r = rows[k];
    out << (k ? ",\n  " : "\n  ") << "{\"dataset\": " << acvo::tools::jsonString(r.dataset)
        << ", \"method\": " << acvo::tools::jsonString(r.method)
        << ", \"setting\": " << acvo::tools::jsonString(r.setting)
        << ", \"best\": " << (r.best ? "true" : "false")
        << ", \"frames\": " << r.trajectory.size() << ", \"rpe_trans\": " << jsonNumber(r.rpe_trans)
        << ", \"rpe_rot_deg\": " << jsonNumber(r.rpe_rot) << ", \"ate\": " << jsonNumber(r.ate)
        << ", \"lost\": " << r.lost << ", \"offset_s\": " << jsonNumber(r.offset)
        << ", \"offset_found\": " << (r.offset_found ? "true" : "false") << ", \"offset_refused\": "
        << (r.offset_refused.empty() ? "null" : acvo::tools::jsonString(r.offset_refused))
        << ", \"median_ms\": " << jsonNumber(median(r.median_ms))
        << ", \"p90_ms\": " << jsonNumber(median(r.p90_ms))
        << ", \"cpu_median_ms\": " << jsonNumber(median(r.cpu_median_ms))
        << ", \"median_ms_runs\": " << jsonList(r.median_ms)
        << ", \"spread_percent\": " << jsonNumber(spreadPercent(r.median_ms))
        << ", \"median_vs_rgbd\": " << jsonNumber(median(r.ratio))
        << ", \"vs_rgbd_runs\": " << jsonList(r.ratio) << "}";
  }
  out << "\n]}\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kDescription, "acvo_compare"};
  Options opt;
  if (const auto status = parseOptions(app, opt, argc, argv)) return *status;
  try {
    acvo::Params params;
    try {
      params = acvo::tools::loadToolParams(opt.config, opt.sets);
    } catch (const std::exception& e) {  // a malformed --set, an unknown key, a bad config
      return acvo::tools::usageError(app, e.what());
    }
    std::vector<Row> rows;
    std::vector<std::string> notes;  // printed below the table
    for (const auto& folder : opt.datasets) {
      const acvo::TumDataset data(folder, opt.camera);
      // The dataset's frames used: every stride-th, at most --frames of them.
      std::vector<std::size_t> index;
      for (std::size_t i = 0; i < data.size(); i += std::size_t(opt.stride)) {
        if (opt.frames >= 0 && index.size() >= std::size_t(opt.frames)) break;
        index.push_back(i);
      }
      std::vector<acvo::Frame> frames;
      frames.reserve(index.size());
      for (const std::size_t i : index) frames.push_back(data.loadFrame(i));
      if (frames.empty()) throw std::runtime_error(folder + ": no frames");
      const std::string dataset =
          baseName(folder) + (opt.stride > 1 ? "_every" + std::to_string(opt.stride) : "");
      std::vector<Entry> entries =
          entriesFor(opt, params, data, dataset, startPose(data, frames.front().stamp));
      for (int run = 0; run < opt.repeat; ++run) runOnce(entries, frames, index, data, run == 0);
      double offset = opt.offset.value_or(0.0);
      std::string refused;
      if (!opt.offset && data.groundtruth()) {
        std::vector<acvo::Trajectory> trajectories;
        for (const auto& e : entries) trajectories.push_back(e.row.trajectory);
        try {
          offset = acvo::estimateClockOffset(*data.groundtruth(), trajectories).offset;
          notes.push_back("# " + dataset + ": the frames' stamps " + milliseconds(offset) +
                          " against the reference's (--offset auto)");
        } catch (const std::exception& e) {
          refused = e.what();
          notes.push_back("# " + dataset + ": evaluated at offset 0: " + refused);
        }
      }
      for (auto& e : entries) {
        evaluate(e.row, data, offset);
        e.row.offset_found = !opt.offset && refused.empty() && data.groundtruth();
        e.row.offset_refused = refused;
      }

      // The best setting of each peer, and the speed ratio to the best RgbdOdometry, per run.
      const auto best = bestRows(entries, opt.label);
      const auto rgbd = best.find("rgbd");
      for (auto& e : entries) {
        for (int run = 0; run < opt.repeat; ++run) {
          e.row.ratio.push_back(rgbd == best.end()
                                    ? NAN
                                    : e.row.median_ms[std::size_t(run)] /
                                          entries[rgbd->second].row.median_ms[std::size_t(run)]);
        }
      }
      for (std::size_t k = 0; k < entries.size(); ++k) {
        Row& row = entries[k].row;
        if (!opt.trajectories.empty()) {
          const bool plain = row.method == opt.label && opt.threads.size() == 1;
          acvo::writeTrajectory(
              opt.trajectories + "/" + dataset + "-" + row.method +
                  (plain ? "" : "-" + row.setting) + ".txt",
              row.trajectory, row.method + " " + row.setting + " on " + folder);
        }
        rows.push_back(row);
        // After a peer's last setting, its best one again, named as such.
        const bool last_of_method =
            k + 1 == entries.size() || entries[k + 1].row.method != row.method;
        const auto b = best.find(row.method);
        if (last_of_method && b != best.end() &&
            opt.peer_max_depth.size() * opt.peer_guess.size() > 1) {
          Row best_row = entries[b->second].row;
          best_row.method += "_best";
          best_row.best = true;
          rows.push_back(std::move(best_row));
        }
      }
    }
    printTable(rows, opt);
    for (const std::string& note : notes) std::printf("%s\n", note.c_str());
    if (!opt.json.empty()) writeJson(rows, opt);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "acvo_compare: " << e.what() << "\n";
    return 2;
  }
}
