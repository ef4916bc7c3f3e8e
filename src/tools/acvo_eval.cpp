// acvo_eval: relative pose error and absolute trajectory error of an estimated trajectory
// against ground truth, both in TUM format, with the TUM benchmark tools' semantics.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "acvo/dataset/evaluation.hpp"
#include "acvo/dataset/tum.hpp"
#include "tool_support.hpp"

namespace {

using acvo::tools::jsonString;

namespace fs = std::filesystem;

constexpr int kError = 2;
constexpr int kPlotFailed = 3;

constexpr const char* kDescription =
    R"(Relative pose error (as evaluate_rpe.py --fixed_delta) and absolute trajectory error (as
evaluate_ate.py) of EST against GT, both TUM trajectories "stamp tx ty tz qx qy qz qw".
)";

constexpr const char* kFooter =
    R"(--plot draws the x-y plane and x/y/z over time; it needs /usr/bin/python3 with matplotlib.
--offset auto prints the offset found and EST's frame-to-frame turn error (RMS, deg) at 0 and at
it; the figures are then at that offset. The last line printed is a summary:
  rpe_trans_rmse=<m> rpe_rot_rmse_deg=<deg> ate_rmse=<m> pairs=<rpe pairs> offset=<s>
Exit status: 0 success, 2 bad arguments or input, 3 the plot could not be made.)";

struct Options {
  std::string groundtruth, estimate, json, plot;
  double delta = 1.0;
  acvo::DeltaUnit unit = acvo::DeltaUnit::kSeconds;
  double max_difference = 0.02;
  std::optional<double> offset = 0.0;  // empty: estimated (--offset auto)
};

// The command line into `o`; nullopt to go on, else the exit status.
std::optional<int> parseOptions(CLI::App& app, Options& o, int argc, char** argv) {
  acvo::tools::setUpCommandLine(app, kFooter);
  app.add_option("--groundtruth", o.groundtruth, "the ground truth")->type_name("GT")->required();
  app.add_option("--estimate", o.estimate, "the estimated trajectory")
      ->type_name("EST")
      ->required();
  app.add_option("--delta", o.delta, "RPE delta")
      ->type_name("D")
      ->capture_default_str()
      ->transform(acvo::tools::anyNumber<double>());
  app.add_option_function<std::string>(
         "--delta-unit",
         [&o](const std::string& unit) { o.unit = acvo::deltaUnitFromString(unit); },
         "seconds, frames, metres travelled, rotation accumulated")
      ->type_name("s|f|m|rad|deg")
      ->default_str(acvo::toString(o.unit))
      ->check(CLI::Validator(
          [](std::string& unit) -> std::string {
            try {
              acvo::deltaUnitFromString(unit);  // the units are the library's to name
            } catch (const std::invalid_argument& e) {
              return e.what();
            }
            return "";
          },
          ""));
  app.add_option("--max-difference", o.max_difference, "ATE stamp association limit in seconds")
      ->type_name("S")
      ->capture_default_str()
      ->transform(acvo::tools::anyNumber<double>());
  acvo::tools::addOffsetOption(
      app, o.offset,
      "added to EST's stamps where they are looked up in GT (a clock offset; auto: the one at "
      "which EST's frame-to-frame turns agree best with GT's)");
  app.add_option("--json", o.json, "write every figure as JSON")->type_name("FILE");
  app.add_option("--plot", o.plot, "plot the ATE-aligned estimate against ground truth")
      ->type_name("FILE.png");
  return acvo::tools::parseCommandLine(app, argc, argv);
}

acvo::Trajectory readTrajectoryFile(const std::string& path) {
  if (!fs::is_regular_file(path)) throw std::runtime_error("no such file: " + path);
  return acvo::readTrajectory(path);
}

void printStats(const std::string& label, const acvo::ErrorStats& s, const char* unit) {
  const std::pair<const char*, double> rows[] = {{"rmse", s.rmse},     {"mean", s.mean},
                                                 {"median", s.median}, {"std", s.std},
                                                 {"min", s.min},       {"max", s.max}};
  for (const auto& [name, value] : rows) {
    std::printf("%s.%s %.6f %s\n", label.c_str(), name, value, unit);
  }
}

std::string jsonStats(const acvo::ErrorStats& s) {
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer),
                "{\"rmse\": %.12g, \"mean\": %.12g, \"median\": %.12g, \"std\": %.12g, "
                "\"min\": %.12g, \"max\": %.12g, \"count\": %zu}",
                s.rmse, s.mean, s.median, s.std, s.min, s.max, s.count);
  return buffer;
}

void writeJson(const Options& o, double offset, const acvo::RpeResult& rpe,
               const acvo::AteResult& ate) {
  std::ofstream out(o.json);
  out.precision(12);
  out << "{\n  \"groundtruth\": " << jsonString(o.groundtruth)
      << ",\n  \"estimate\": " << jsonString(o.estimate) << ",\n  \"offset_s\": " << offset
      << ", \"offset_estimated\": " << (o.offset ? "false" : "true")
      << ",\n  \"rpe\": {\"delta\": " << o.delta
      << ", \"delta_unit\": " << jsonString(acvo::toString(o.unit)) << ", \"pairs\": " << rpe.pairs
      << ",\n    \"trans_m\": " << jsonStats(rpe.trans)
      << ",\n    \"rot_deg\": " << jsonStats(rpe.rot_deg)
      << "},\n  \"ate\": {\"max_difference\": " << o.max_difference << ", \"pairs\": " << ate.pairs
      << ",\n    \"trans_m\": " << jsonStats(ate.trans) << ",\n    \"alignment\": [";
  const Eigen::Matrix4d m = ate.alignment.matrix();
  for (int r = 0; r < 4; ++r) {
    out << (r ? ", [" : "[");
    for (int c = 0; c < 4; ++c) out << (c ? ", " : "") << m(r, c);
    out << "]";
  }
  out << "]}\n}\n";
  if (!out) throw std::runtime_error("cannot write " + o.json);
}

// The plotting script: beside the installed tool, else in the source tree's scripts/.
fs::path plotScript() {
  if (const char* env = std::getenv("ACVO_PLOT_SCRIPT")) return env;
  std::error_code ec;
  fs::path beside = fs::read_symlink("/proc/self/exe", ec).parent_path() / "plot_trajectories.py";
  if (!ec && fs::exists(beside)) return beside;
  return fs::path(ACVO_SCRIPTS_DIR) / "plot_trajectories.py";
}

int runProcess(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

// Writes the aligned estimate to a temporary file and hands both trajectories to the script.
bool plot(const Options& o, const acvo::Trajectory& estimate, const acvo::RpeResult& rpe,
          const acvo::AteResult& ate) {
  const std::string python = "/usr/bin/python3";
  if (access(python.c_str(), X_OK) != 0) {
    std::cerr << "acvo_eval: --plot needs " << python
              << " with matplotlib (Debian: python3-matplotlib); no plot written\n";
    return false;
  }
  const fs::path script = plotScript();
  if (!fs::exists(script)) {
    std::cerr << "acvo_eval: plotting script " << script << " not found; no plot written\n";
    return false;
  }
  acvo::Trajectory aligned = estimate;
  for (acvo::StampedPose& p : aligned) p.pose = ate.alignment * p.pose;
  const fs::path temp =
      fs::temp_directory_path() / ("acvo_eval_aligned_" + std::to_string(getpid()) + ".txt");
  acvo::writeTrajectory(temp.string(), aligned, "estimate after ATE alignment");
  char title[256];
  std::snprintf(title, sizeof(title), "ATE RMSE %.4f m, RPE RMSE %.4f m / %.3f deg per %g %s",
                ate.trans.rmse, rpe.trans.rmse, rpe.rot_deg.rmse, o.delta,
                acvo::toString(o.unit).c_str());
  const int status =
      runProcess({python, script.string(), "--groundtruth", o.groundtruth, "--estimate",
                  temp.string(), "--output", o.plot, "--title", title});
  fs::remove(temp);
  if (status != 0) {
    std::cerr << "acvo_eval: the plotting script failed (status " << status
              << "); no plot written\n";
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kDescription, "acvo_eval"};
  Options o;
  if (const auto status = parseOptions(app, o, argc, argv)) return *status;

  acvo::Trajectory groundtruth, estimate;
  acvo::RpeResult rpe;
  acvo::AteResult ate;
  double offset = o.offset.value_or(0.0);
  std::optional<acvo::ClockOffset> clock;
  try {
    groundtruth = readTrajectoryFile(o.groundtruth);
    estimate = readTrajectoryFile(o.estimate);
    if (!o.offset) {
      clock = acvo::estimateClockOffset(groundtruth, {estimate});
      offset = clock->offset;
    }
    rpe = acvo::computeRpe(groundtruth, estimate, o.delta, o.unit, offset);
    ate = acvo::computeAte(groundtruth, estimate, o.max_difference, offset);
    if (!o.json.empty()) writeJson(o, offset, rpe, ate);
  } catch (const std::exception& e) {
    std::cerr << "acvo_eval: " << e.what() << "\n";
    return kError;
  }

  if (clock) {
    std::printf("# clock offset, from %zu frame-to-frame turns\n", clock->turns);
    std::printf("offset %.6f s\n", offset);
    std::printf("turn_error_rms_at_zero %.6f deg\n", clock->turn_rms_at_zero_deg.front());
    std::printf("turn_error_rms_at_offset %.6f deg\n", clock->turn_rms_deg.front());
  }

  std::printf("# relative pose error, delta %g %s\n", o.delta, acvo::toString(o.unit).c_str());
  std::printf("compared_pose_pairs %zu pairs\n", rpe.pairs);
  printStats("translational_error", rpe.trans, "m");
  printStats("rotational_error", rpe.rot_deg, "deg");
  std::printf("# absolute trajectory error\n");
  std::printf("compared_pose_pairs %zu pairs\n", ate.pairs);
  printStats("absolute_translational_error", ate.trans, "m");

  bool plotted = true;
  if (!o.plot.empty()) {
    try {
      plotted = plot(o, estimate, rpe, ate);
    } catch (const std::exception& e) {
      std::cerr << "acvo_eval: plot: " << e.what() << "\n";
      plotted = false;
    }
  }
  std::printf("rpe_trans_rmse=%.9f rpe_rot_rmse_deg=%.9f ate_rmse=%.9f pairs=%zu offset=%.6f\n",
              rpe.trans.rmse, rpe.rot_deg.rmse, ate.trans.rmse, rpe.pairs, offset);
  return plotted ? 0 : kPlotFailed;
}
