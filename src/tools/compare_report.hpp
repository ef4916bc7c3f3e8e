// acvo_compare's rows and how they are reported: the table on stdout, the JSON file, and the
// choice of each peer's best setting.
#pragma once

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "acvo/dataset/evaluation.hpp"

namespace acvo::tools {

// One row of the table: a method at one setting over one dataset.
struct CompareRow {
  std::string dataset, method, setting;
  bool best = false;  // a <peer>_best row
  Trajectory trajectory;
  long lost = 0;
  double offset = 0.0;         // s, added to the stamps against the reference's
  bool offset_found = false;   // by --offset auto
  std::string offset_refused;  // why --offset auto found none (then offset 0)
  double rpe_trans = NAN, rpe_rot = NAN, ate = NAN;
  // Per run: the median and 90th percentile over frames of the wall and CPU times (ms), and
  // the median as a ratio of the best RgbdOdometry row's median in that run.
  std::vector<double> median_ms, p90_ms, cpu_median_ms, ratio;
};

// What the table's first line and the JSON's header say of the run.
struct CompareRun {
  std::vector<int> threads;  // acvo's, one row per value
  int repeat = 1;
  std::string camera;            // --camera, empty: each folder's own
  std::optional<double> offset;  // --offset, empty: auto
};

// "1_thread", "2_threads", "all_cores" (0).
std::string threadsSetting(int threads);

// "+12.3 ms".
std::string milliseconds(double seconds);

// Per peer (every method but acvo_label), the index of its best row: the fewest lost frames,
// then the lowest sum of the translation and rotation errors, each divided by its mean over the
// peer's settings.
std::map<std::string, std::size_t> bestRows(const std::vector<CompareRow>& rows,
                                            const std::string& acvo_label);

void printCompareTable(const std::vector<CompareRow>& rows, const CompareRun& run);

// Throws std::runtime_error when the file cannot be written.
void writeCompareJson(const std::vector<CompareRow>& rows, const CompareRun& run,
                      const std::string& path);

}  // namespace acvo::tools
