// The offset between a reference's clock and the estimates' stamps (estimateClockOffset,
// evaluation.hpp): the offset at which the estimates' frame-to-frame turns agree best with the
// reference's.
#include "acvo/dataset/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "stamp_association.hpp"
#include "trajectory_stamps.hpp"

namespace acvo {
namespace {

using detail::associateStamps;
using detail::byStamp;
using detail::medianInterval;
using detail::stampsOf;

constexpr double kOffsetStep = 5e-4;        // s, the search's grid
constexpr std::size_t kMinTurns = 10;       // turns compared, at least
constexpr double kObservableRise = 1.05;    // the curve's ends over its least value, at least
constexpr double kReferenceRateRatio = 0.5;  // the reference's interval over the frames', at most
constexpr double kSameInstant = 1e-4;       // s: a reference stamp this close is a frame's own
constexpr double kOwnStampsShare = 0.9;     // frames at reference stamps, at most (of all)

// The reference sorted by stamp, its stamps and their median interval.
struct Reference {
  Trajectory poses;
  std::vector<double> stamps;
  double interval = 0.0;
};

// The reference's orientation at time t (slerp between the poses around it), or none where t
// is outside it or falls in a gap longer than twice its median interval (computeRpe's limit).
std::optional<Eigen::Quaterniond> orientationAt(const Reference& ref, double t) {
  const auto after = std::upper_bound(ref.stamps.begin(), ref.stamps.end(), t);
  if (after == ref.stamps.begin() || after == ref.stamps.end()) return std::nullopt;
  const std::size_t k = std::size_t(after - ref.stamps.begin());
  const double t0 = ref.stamps[k - 1], t1 = ref.stamps[k];
  if (t1 - t0 > 2.0 * ref.interval) return std::nullopt;
  const Eigen::Quaterniond q0(ref.poses[k - 1].pose.linear()), q1(ref.poses[k].pose.linear());
  return q0.slerp((t - t0) / (t1 - t0), q1);
}

// The angle (rad) between the estimate's turn from pose a to pose b and the reference's over
// their stamps + offset; none where the reference does not cover them.
std::optional<double> turnError(const Reference& ref, const StampedPose& a, const StampedPose& b,
                                double offset) {
  const auto ra = orientationAt(ref, a.stamp + offset);
  const auto rb = orientationAt(ref, b.stamp + offset);
  if (!ra || !rb) return std::nullopt;
  const Eigen::Quaterniond turn(a.pose.linear().transpose() * b.pose.linear());
  return (ra->conjugate() * *rb).angularDistance(turn);
}

// The offsets searched: -half ... half steps.
double offsetAt(std::size_t g, int half) { return (int(g) - half) * kOffsetStep; }

// An estimate's sum of squared turn errors at every offset searched, over the turns (pose k - 1
// to pose k) the reference covers at every one of them; `turns` counts those.
std::vector<double> turnErrorCurve(const Reference& ref, const Trajectory& est, int half,
                                   std::size_t& turns) {
  const std::size_t grid = 2 * std::size_t(half) + 1;
  std::vector<double> sum(grid, 0.0), squares(grid);
  turns = 0;
  for (std::size_t k = 1; k < est.size(); ++k) {
    bool covered = true;
    for (std::size_t g = 0; g < grid && covered; ++g) {
      const auto e = turnError(ref, est[k - 1], est[k], offsetAt(g, half));
      covered = e.has_value();
      if (covered) squares[g] = *e * *e;
    }
    if (!covered) continue;
    for (std::size_t g = 0; g < grid; ++g) sum[g] += squares[g];
    ++turns;
  }
  return sum;
}

// The best grid point of the summed curves, refined by the parabola through it and its
// neighbours; throws where the curve does not show an offset.
double bestOffset(const std::vector<double>& total, int half, double max_offset) {
  const std::size_t best =
      std::size_t(std::min_element(total.begin(), total.end()) - total.begin());
  const std::string too_little =
      "clock offset: the reference turns too little for its clock to show";
  if (*std::max_element(total.begin(), total.end()) < kObservableRise * total[best]) {
    throw std::runtime_error(too_little);
  }
  if (best == 0 || best + 1 == total.size()) {
    throw std::runtime_error("clock offset: the best offset is at the edge of the search, +-" +
                             std::to_string(max_offset) + " s");
  }
  if (std::min(total.front(), total.back()) < kObservableRise * total[best]) {
    throw std::runtime_error(too_little);
  }
  const double lo = total[best - 1], mid = total[best], hi = total[best + 1];
  const double curvature = lo - 2.0 * mid + hi;
  const double shift = curvature > 0.0 ? 0.5 * (lo - hi) / curvature : 0.0;
  return offsetAt(best, half) + std::clamp(shift, -0.5, 0.5) * kOffsetStep;
}

// The reference sorted by stamp, with its stamps and their median interval; throws where it has
// fewer than 2 poses.
Reference referenceOf(const Trajectory& groundtruth) {
  Reference ref;
  ref.poses = byStamp(groundtruth);
  if (ref.poses.size() < 2) {
    throw std::runtime_error("clock offset: the reference has fewer than 2 poses");
  }
  ref.stamps = stampsOf(ref.poses);
  ref.interval = medianInterval(ref.stamps);
  return ref;
}

// The estimates sorted by stamp. Between a reference's samples its turn is an interpolation:
// sampled no faster than the frames, the offset found would be the one at which the
// interpolation smooths best; throws there. A reference whose poses carry the frames' own
// stamps (one pose per recorded frame, as 7-Scenes'; its frames kept one in K, `--stride`) has
// no clock of its own either, however often it is sampled against the frames kept; throws too.
std::vector<Trajectory> sortedEstimates(const std::vector<Trajectory>& estimates,
                                        const Reference& ref) {
  std::vector<Trajectory> sorted;
  for (const Trajectory& trajectory : estimates) {
    sorted.push_back(byStamp(trajectory));
    if (sorted.back().size() <= 2) continue;
    const std::vector<double> stamps = stampsOf(sorted.back());
    const double frame_interval = medianInterval(stamps);
    if (!(ref.interval <= kReferenceRateRatio * frame_interval)) {
      throw std::runtime_error(
          "clock offset: the reference is sampled every " + std::to_string(ref.interval) +
          " s, not at least twice as often as the frames (every " +
          std::to_string(frame_interval) + " s): its clock cannot be told from its frames'");
    }
    const std::size_t own = associateStamps(stamps, ref.stamps, kSameInstant).size();
    if (double(own) > kOwnStampsShare * double(stamps.size())) {
      throw std::runtime_error("clock offset: " + std::to_string(own) + " of the " +
                               std::to_string(stamps.size()) +
                               " frames' stamps are the reference's own: a reference of one "
                               "pose per frame has no clock of its own");
    }
  }
  return sorted;
}

// The estimates' turn error curves, each divided by its own least value, weighted and summed;
// `turns` counts the turns compared. Throws where fewer than kMinTurns turns or no estimate
// contribute.
std::vector<double> summedCurve(const Reference& ref, const std::vector<Trajectory>& sorted,
                                const std::vector<double>& weights, int half, double max_offset,
                                std::size_t& turns) {
  std::vector<double> total(2 * std::size_t(half) + 1, 0.0);
  std::size_t contributing = 0;
  for (std::size_t e = 0; e < sorted.size(); ++e) {
    std::size_t est_turns = 0;
    const std::vector<double> sum = turnErrorCurve(ref, sorted[e], half, est_turns);
    turns += est_turns;
    const double least = *std::min_element(sum.begin(), sum.end());
    // Nothing to compare, or a copy of the reference.
    if (est_turns == 0 || !(least > 0.0)) continue;
    const double weight = weights.empty() ? 1.0 : weights[e];
    for (std::size_t g = 0; g < total.size(); ++g) total[g] += weight * sum[g] / least;
    ++contributing;
  }
  if (turns < kMinTurns || contributing == 0) {
    throw std::runtime_error("clock offset: " + std::to_string(turns) +
                             " frame-to-frame turns are covered by the reference at every offset "
                             "within +-" + std::to_string(max_offset) + " s (at least " +
                             std::to_string(kMinTurns) + " needed)");
  }
  return total;
}

// Each estimate's RMS turn error (deg) at 0 and at result.offset, over the turns the reference
// covers at both.
void addTurnRms(const Reference& ref, const std::vector<Trajectory>& sorted, ClockOffset& result) {
  constexpr double kToDeg = 180.0 / M_PI;
  for (const Trajectory& est : sorted) {
    double at_zero = 0.0, at_offset = 0.0;
    std::size_t n = 0;
    for (std::size_t k = 1; k < est.size(); ++k) {
      const auto zero = turnError(ref, est[k - 1], est[k], 0.0);
      const auto found = turnError(ref, est[k - 1], est[k], result.offset);
      if (!zero || !found) continue;
      at_zero += *zero * *zero;
      at_offset += *found * *found;
      ++n;
    }
    const double count = double(n);
    result.turn_rms_at_zero_deg.push_back(n ? std::sqrt(at_zero / count) * kToDeg : NAN);
    result.turn_rms_deg.push_back(n ? std::sqrt(at_offset / count) * kToDeg : NAN);
  }
}

}  // namespace

ClockOffset estimateClockOffset(const Trajectory& groundtruth,
                                const std::vector<Trajectory>& estimates,
                                const std::vector<double>& weights, double max_offset) {
  const Reference ref = referenceOf(groundtruth);
  const int half = int(std::lround(max_offset / kOffsetStep));
  if (half < 1) throw std::runtime_error("clock offset: the search range is below its step");
  const bool weighted = std::all_of(weights.begin(), weights.end(),
                                    [](double w) { return std::isfinite(w) && w > 0.0; });
  if (!weights.empty() && (weights.size() != estimates.size() || !weighted)) {
    throw std::invalid_argument("clock offset: one positive weight per estimate, or none");
  }
  const std::vector<Trajectory> sorted = sortedEstimates(estimates, ref);
  ClockOffset result;
  const std::vector<double> total =
      summedCurve(ref, sorted, weights, half, max_offset, result.turns);
  result.offset = bestOffset(total, half, max_offset);
  addTurnRms(ref, sorted, result);
  return result;
}

}  // namespace acvo
