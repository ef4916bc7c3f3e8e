// acvo_compare's table, JSON and best settings (compare_report.hpp).
#include "compare_report.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <stdexcept>

#include "tool_support.hpp"

namespace acvo::tools {
namespace {

double median(std::vector<double> v) {
  return percentile(std::move(v), 0.5);
}

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

template <typename T>
std::string jsonList(const std::vector<T>& v) {
  std::string s = "[";
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + jsonNumber(double(v[k]));
  return s + "]";
}

// The mean of the finite values (a start too near the end to be evaluated has none).
double finiteMean(const std::vector<double>& v) {
  double sum = 0.0;
  int n = 0;
  for (double x : v) {
    if (!std::isfinite(x)) continue;
    sum += x;
    ++n;
  }
  return n ? sum / n : NAN;
}

template <typename T>
void append(std::vector<T>& to, const std::vector<T>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

// RPE over 1 s and ATE of one row at `offset`; a row that cannot be evaluated keeps NaN, and
// says why on stderr.
void evaluate(CompareRow& row, const Trajectory& reference, double offset) {
  try {
    const RpeResult rpe = computeRpe(reference, row.trajectory, 1.0, DeltaUnit::kSeconds, offset);
    row.rpe_trans = rpe.trans.rmse;
    row.rpe_rot = rpe.rot_deg.rmse;
    row.ate = computeAte(reference, row.trajectory, 0.02, offset).trans.rmse;
  } catch (const std::exception& e) {
    std::cerr << "acvo_compare: " << row.dataset << " " << row.method << " " << row.setting
              << ": no evaluation: " << e.what() << "\n";
  }
}

}  // namespace

void evaluateRows(std::vector<CompareRow>& rows, const std::optional<Trajectory>& reference,
                  const std::optional<double>& offset, const std::string& name,
                  std::vector<std::string>& notes) {
  double at = offset.value_or(0.0);
  std::string refused;
  if (!offset && reference) {
    // Every method one vote: each of its rows (settings, thread counts) 1/K of it.
    std::map<std::string, int> rows_of;
    for (const auto& row : rows) ++rows_of[row.method];
    std::vector<Trajectory> trajectories;
    std::vector<double> weights;
    for (const auto& row : rows) {
      trajectories.push_back(row.trajectory);
      weights.push_back(1.0 / rows_of[row.method]);
    }
    try {
      at = estimateClockOffset(*reference, trajectories, weights).offset;
      notes.push_back("# " + name + ": the frames' stamps " + milliseconds(at) +
                      " against the reference's (--offset auto)");
    } catch (const std::exception& e) {
      refused = e.what();
      notes.push_back("# " + name + ": evaluated at offset 0: " + refused);
    }
  }
  for (auto& row : rows) {
    row.offset = at;
    if (reference) evaluate(row, *reference, at);
    row.offset_found = !offset && refused.empty() && reference;
    row.offset_refused = refused;
  }
}

std::string threadsSetting(int threads) {
  if (threads == 0) return "all_cores";
  return std::to_string(threads) + (threads == 1 ? "_thread" : "_threads");
}

std::string milliseconds(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%+.1f ms", 1e3 * seconds);
  return buf;
}

void poolStarts(std::vector<CompareRow>& pooled, std::vector<CompareRow> rows) {
  for (auto& row : rows) {
    row.start_rpe_trans = {row.rpe_trans};
    row.start_rpe_rot = {row.rpe_rot};
    row.start_ate = {row.ate};
  }
  if (pooled.empty()) {
    pooled = std::move(rows);
    return;
  }
  if (pooled.size() != rows.size()) throw std::logic_error("poolStarts: rows differ");
  for (std::size_t k = 0; k < rows.size(); ++k) {
    CompareRow &to = pooled[k], &from = rows[k];
    append(to.starts, from.starts);
    append(to.start_rpe_trans, from.start_rpe_trans);
    append(to.start_rpe_rot, from.start_rpe_rot);
    append(to.start_ate, from.start_ate);
    to.rpe_trans = finiteMean(to.start_rpe_trans);
    to.rpe_rot = finiteMean(to.start_rpe_rot);
    to.ate = finiteMean(to.start_ate);
    to.lost += from.lost;
    to.frames += from.frames;
    append(to.median_ms, from.median_ms);
    append(to.p90_ms, from.p90_ms);
    append(to.cpu_median_ms, from.cpu_median_ms);
  }
}

std::map<std::string, std::size_t> bestRows(const std::vector<CompareRow>& rows,
                                            const std::string& acvo_label) {
  std::map<std::string, std::vector<std::size_t>> by_method;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (rows[k].method != acvo_label) by_method[rows[k].method].push_back(k);
  }
  std::map<std::string, std::size_t> best;
  for (const auto& [method, settings] : by_method) {
    double mean_t = 0.0, mean_r = 0.0;
    for (std::size_t k : settings) {
      mean_t += rows[k].rpe_trans / double(settings.size());
      mean_r += rows[k].rpe_rot / double(settings.size());
    }
    const auto worse = [&](std::size_t a, std::size_t b) {  // a is worse than b
      const CompareRow &ra = rows[a], &rb = rows[b];
      if (ra.lost != rb.lost) return ra.lost > rb.lost;
      const double sa = ra.rpe_trans / mean_t + ra.rpe_rot / mean_r;
      const double sb = rb.rpe_trans / mean_t + rb.rpe_rot / mean_r;
      return !(sa <= sb) && std::isfinite(sb);  // NaN (no ground truth) is never better
    };
    std::size_t chosen = settings.front();
    for (std::size_t k : settings) {
      if (worse(chosen, k)) chosen = k;
    }
    best[method] = chosen;
  }
  return best;
}

void printCompareTable(const std::vector<CompareRow>& rows, const CompareRun& run) {
  std::string threads;
  for (int t : run.threads) threads += (threads.empty() ? "" : ",") + threadsSetting(t);
  const std::string camera = run.camera.empty() ? "" : "; camera: " + run.camera;
  const std::string offset =
      run.offset && *run.offset != 0.0
          ? "; the frames' stamps " + milliseconds(*run.offset) + " against the reference's"
          : "";
  std::string starts;
  for (long s : run.starts) starts += (starts.empty() ? "" : ",") + std::to_string(s);
  if (run.starts.size() > 1) {
    starts = "; errors: the mean over the runs from frames " + starts + ", lost: their sum";
  } else {
    starts = run.starts.front() != 0 ? "; from frame " + starts : "";
  }
  const int runs = run.repeat * int(run.starts.size());
  std::printf(
      "# acvo on %s; OpenCV odometries serial, as OpenCV's TUM sample runs them (NaN "
      "holes; _guess: the last motion as initial guess); times: median over frames, "
      "median of %d run%s interleaved frame by frame; vs_rgbd: median time / the best "
      "RgbdOdometry setting's, per run%s%s%s\n",
      threads.c_str(), runs, runs == 1 ? "" : "s", camera.c_str(), offset.c_str(), starts.c_str());
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

void writeCompareJson(const std::vector<CompareRow>& rows, const CompareRun& run,
                      const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "{\"rpe_delta_s\": 1, \"repeat\": " << run.repeat
      << ", \"starts\": " << jsonList(run.starts);
  if (!run.camera.empty()) out << ", \"camera\": " << jsonString(run.camera);
  out << ", \"acvo_threads\": " << jsonList(run.threads) << ", \"runs\": [";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const CompareRow& r = rows[k];
    out << (k ? ",\n  " : "\n  ") << "{\"dataset\": " << jsonString(r.dataset)
        << ", \"method\": " << jsonString(r.method) << ", \"setting\": " << jsonString(r.setting)
        << ", \"best\": " << (r.best ? "true" : "false") << ", \"frames\": " << r.frames
        << ", \"rpe_trans\": " << jsonNumber(r.rpe_trans)
        << ", \"rpe_rot_deg\": " << jsonNumber(r.rpe_rot) << ", \"ate\": " << jsonNumber(r.ate)
        << ", \"starts\": " << jsonList(r.starts)
        << ", \"rpe_trans_starts\": " << jsonList(r.start_rpe_trans)
        << ", \"rpe_rot_deg_starts\": " << jsonList(r.start_rpe_rot)
        << ", \"ate_starts\": " << jsonList(r.start_ate) << ", \"lost\": " << r.lost
        << ", \"offset_s\": " << jsonNumber(r.offset)
        << ", \"offset_found\": " << (r.offset_found ? "true" : "false") << ", \"offset_refused\": "
        << (r.offset_refused.empty() ? "null" : jsonString(r.offset_refused))
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

}  // namespace acvo::tools
