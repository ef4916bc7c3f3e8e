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

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "acvo/dataset/evaluation.hpp"
#include "acvo/dataset/tum.hpp"
#include "acvo/odometry/odometry.hpp"
#include "acvo/params.hpp"
#include "compare_methods.hpp"
#include "compare_report.hpp"
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
--starts runs each folder from several first frames and gives each row the mean of their
errors: a short folder from one first frame is one draw of its errors, and a change is better
judged over several.
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
  std::vector<long> starts{0};
  int repeat = 1;
  std::vector<std::string> peer_guess{"none", "last"};
  std::optional<double> offset = 0.0;  // empty: estimated per dataset (--offset auto)
};

// Which methods run, in which settings (each a row), and how often.
void addMethodOptions(CLI::App& app, Options& o) {
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
}

// The frames each method is given, acvo's parameters and what is written.
void addInputOptions(CLI::App& app, Options& o) {
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
  app.add_option("--starts", o.starts,
                 "first frames (0-based, before --stride), one run of every row from each; with "
                 "more than one, the errors are the means over them (where evaluated), the lost "
                 "frames their sum")
      ->type_name("LIST")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->default_str("0")
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
}

// The command line into `o`; nullopt to go on, else the exit status.
std::optional<int> parseOptions(CLI::App& app, Options& o, int argc, char** argv) {
  acvo::tools::setUpCommandLine(app, kFooter);
  app.add_option("DATASET_DIR", o.datasets, "TUM RGB-D folders")->type_name("")->required();
  addMethodOptions(app, o);
  addInputOptions(app, o);
  if (const auto status = acvo::tools::parseCommandLine(app, argc, argv)) return status;
  // --methods "" or ",": CLI11 leaves the list empty.
  if (o.methods.empty()) return acvo::tools::usageError(app, "--methods is empty");
  if (o.peer_max_depth.empty()) return acvo::tools::usageError(app, "--peer-max-depth is empty");
  if (o.peer_guess.empty()) return acvo::tools::usageError(app, "--peer-guess is empty");
  if (o.threads.empty()) return acvo::tools::usageError(app, "--threads is empty");
  if (o.starts.empty()) return acvo::tools::usageError(app, "--starts is empty");
  return std::nullopt;
}

using Row = acvo::tools::CompareRow;

Row makeRow(const std::string& dataset, const std::string& method, const std::string& setting) {
  Row row;
  row.dataset = dataset;
  row.method = method;
  row.setting = setting;
  return row;
}

// What one row runs: its row and how to make a fresh method for each run.
struct Entry {
  Row row;
  std::function<std::unique_ptr<acvo::tools::Method>()> make;
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
        entries.push_back(
            {makeRow(dataset, opt.label, acvo::tools::threadsSetting(threads)),
             [p, start] { return std::make_unique<acvo::tools::AcvoMethod>(p, start); }});
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
                             return std::make_unique<acvo::tools::PeerMethod>(setup, camera, start);
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
  std::vector<std::unique_ptr<acvo::tools::Method>> methods;
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

// The rows of one folder run from frame `first`, evaluated, their trajectories written.
std::vector<Row> runFrom(const Options& opt, const acvo::Params& params,
                         const acvo::TumDataset& data, const std::string& dataset, long first,
                         std::vector<std::string>& notes) {
  // The dataset's frames used: every stride-th from `first`, at most --frames of them.
  std::vector<std::size_t> index;
  for (auto i = std::size_t(first); i < data.size(); i += std::size_t(opt.stride)) {
    if (opt.frames >= 0 && index.size() >= std::size_t(opt.frames)) break;
    index.push_back(i);
  }
  std::vector<acvo::Frame> frames;
  frames.reserve(index.size());
  for (const std::size_t i : index) frames.push_back(data.loadFrame(i));
  if (frames.empty()) {
    throw std::runtime_error(dataset + ": no frames from frame " + std::to_string(first));
  }
  std::vector<Entry> entries =
      entriesFor(opt, params, data, dataset, startPose(data, frames.front().stamp));
  for (int run = 0; run < opt.repeat; ++run) runOnce(entries, frames, index, data, run == 0);
  std::vector<Row> rows;
  for (auto& e : entries) rows.push_back(std::move(e.row));
  const bool several = opt.starts.size() > 1;
  const std::string from = several ? "-from" + std::to_string(first) : "";
  acvo::tools::evaluateRows(rows, data.groundtruth(), opt.offset,
                            several ? dataset + " from frame " + std::to_string(first) : dataset,
                            notes);
  for (auto& row : rows) {
    row.starts = {first};
    row.frames = row.trajectory.size();
    if (opt.trajectories.empty()) continue;
    const bool plain = row.method == opt.label && opt.threads.size() == 1;
    acvo::writeTrajectory(opt.trajectories + "/" + dataset + "-" + row.method +
                              (plain ? "" : "-" + row.setting) + from + ".txt",
                          row.trajectory, row.method + " " + row.setting + " on " + data.folder());
  }
  return rows;
}

// The rows of one folder over every start, each peer's best setting after its last (where it
// has several), and the notes to print below the table.
void compareFolder(const Options& opt, const acvo::Params& params, const std::string& folder,
                   std::vector<Row>& rows, std::vector<std::string>& notes) {
  const acvo::TumDataset data(folder, opt.camera);
  const std::string dataset =
      baseName(folder) + (opt.stride > 1 ? "_every" + std::to_string(opt.stride) : "");
  std::vector<Row> folder_rows;
  for (const long first : opt.starts) {
    acvo::tools::poolStarts(folder_rows, runFrom(opt, params, data, dataset, first, notes));
  }

  // The best setting of each peer, and the speed ratio to the best RgbdOdometry, per run.
  const auto best = acvo::tools::bestRows(folder_rows, opt.label);
  const auto rgbd = best.find("rgbd");
  for (auto& row : folder_rows) {
    for (std::size_t run = 0; run < row.median_ms.size(); ++run) {
      row.ratio.push_back(
          rgbd == best.end() ? NAN : row.median_ms[run] / folder_rows[rgbd->second].median_ms[run]);
    }
  }
  for (std::size_t k = 0; k < folder_rows.size(); ++k) {
    const Row& row = folder_rows[k];
    rows.push_back(row);
    // After a peer's last setting, its best one again, named as such.
    const bool last_of_method =
        k + 1 == folder_rows.size() || folder_rows[k + 1].method != row.method;
    const auto b = best.find(row.method);
    if (last_of_method && b != best.end() &&
        opt.peer_max_depth.size() * opt.peer_guess.size() > 1) {
      Row best_row = folder_rows[b->second];
      best_row.method += "_best";
      best_row.best = true;
      rows.push_back(std::move(best_row));
    }
  }
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
    for (const auto& folder : opt.datasets) compareFolder(opt, params, folder, rows, notes);
    const acvo::tools::CompareRun run{opt.threads, opt.repeat, opt.camera, opt.offset, opt.starts};
    acvo::tools::printCompareTable(rows, run);
    for (const std::string& note : notes) std::printf("%s\n", note.c_str());
    if (!opt.json.empty()) acvo::tools::writeCompareJson(rows, run, opt.json);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "acvo_compare: " << e.what() << "\n";
    return 2;
  }
}
