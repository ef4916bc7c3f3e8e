// acvo_compare's rows, how they are evaluated and pooled over starts, and how they are reported:
// the table on stdout, the JSON file, and the choice of each peer's best setting.
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
  // The first frames the row ran from (--starts), its errors from each, and the frames run.
  std::vector<long> starts;
  std::vector<double> start_rpe_trans, start_rpe_rot, start_ate;
  std::size_t frames = 0;
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
  std::vector<long> starts{0};   // --starts
};

// Every row's RPE over 1 s and ATE against `reference` (none: the figures stay NaN), at
// `offset`, or (empty) at the offset found from all the rows together; what was found, or why
// none was, is added to `notes` under `name`.
void evaluateRows(std::vector<CompareRow>& rows, const std::optional<Trajectory>& reference,
                  const std::optional<double>& offset, const std::string& name,
                  std::vector<std::string>& notes);

// Adds the rows of one start (their figures as evaluated) to `pooled`, row by row (the same
// methods and settings in the same order; the first start's rows begin it): each error becomes
// the mean over the starts where it was evaluated, the lost and run frames their sums, and the
// per-run times of every start are kept together.
void poolStarts(std::vector<CompareRow>& pooled, std::vector<CompareRow> rows);

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
