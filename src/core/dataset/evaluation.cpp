// RPE and ATE as the TUM RGB-D benchmark tools compute them (docs/method.md §8).
#include "acvo/dataset/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "stamp_association.hpp"

namespace acvo {
namespace {

// Indices of the poses sorted by stamp; of poses with equal stamps only the last one given stays
// (the tools read trajectories into dictionaries keyed by stamp).
std::vector<std::size_t> uniqueByStamp(const Trajectory& trajectory) {
  std::vector<std::size_t> order(trajectory.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return trajectory[a].stamp < trajectory[b].stamp;
  });
  std::vector<std::size_t> unique;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k + 1 < order.size() && trajectory[order[k + 1]].stamp == trajectory[order[k]].stamp) {
      continue;
    }
    unique.push_back(order[k]);
  }
  return unique;
}

Trajectory byStamp(const Trajectory& trajectory) {
  Trajectory sorted;
  for (const std::size_t k : uniqueByStamp(trajectory)) sorted.push_back(trajectory[k]);
  return sorted;
}

std::vector<double> stampsOf(const Trajectory& trajectory) {
  std::vector<double> stamps;
  for (const StampedPose& p : trajectory) stamps.push_back(p.stamp);
  return stamps;
}

// evaluate_rpe.py's binary search: the closest value among those the bisection visits, the
// first one met winning ties.
std::size_t findClosestIndex(const std::vector<double>& values, double t) {
  std::size_t begin = 0, end = values.size(), best = 0;
  double difference = std::abs(values[0] - t);
  while (begin < end) {
    const std::size_t middle = (begin + end) / 2;
    if (std::abs(values[middle] - t) < difference) {
      difference = std::abs(values[middle] - t);
      best = middle;
    }
    if (values[middle] == t) return middle;
    if (values[middle] > t) {
      end = middle;
    } else {
      begin = middle + 1;
    }
  }
  return best;
}

double rotationAngle(const Eigen::Matrix3d& r) {
  return std::acos(std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0));
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double medianInterval(const std::vector<double>& stamps) {
  std::vector<double> intervals;
  for (std::size_t k = 1; k < stamps.size(); ++k) intervals.push_back(stamps[k] - stamps[k - 1]);
  return median(intervals);
}

// The value each estimate pose has in the delta's unit (stamps, ordinals, path length, or
// accumulated rotation).
std::vector<double> deltaIndex(const Trajectory& estimate, DeltaUnit unit) {
  std::vector<double> index(estimate.size(), 0.0);
  for (std::size_t k = 0; k < estimate.size(); ++k) {
    switch (unit) {
      case DeltaUnit::kSeconds:
        index[k] = estimate[k].stamp;
        break;
      case DeltaUnit::kFrames:
        index[k] = static_cast<double>(k);
        break;
      case DeltaUnit::kMeters:
      case DeltaUnit::kRadians:
      case DeltaUnit::kDegrees: {
        if (k == 0) break;
        const Eigen::Isometry3d motion = estimate[k].pose.inverse() * estimate[k - 1].pose;
        const double step = unit == DeltaUnit::kMeters ? motion.translation().norm()
                            : unit == DeltaUnit::kRadians
                                ? rotationAngle(motion.linear())
                                : rotationAngle(motion.linear()) * 180.0 / M_PI;
        index[k] = index[k - 1] + step;
        break;
      }
    }
  }
  return index;
}

// Horn's closed form (Umeyama without scale): the rigid motion taking `from` onto `to` in the
// least-squares sense, from the SVD of the cross-covariance with the reflection case fixed.
Eigen::Isometry3d hornAlignment(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  const Eigen::Vector3d from_mean = from.rowwise().mean(), to_mean = to.rowwise().mean();
  const Eigen::Matrix3d covariance =
      (to.colwise() - to_mean) * (from.colwise() - from_mean).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s(2, 2) = -1.0;
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();
  alignment.linear() = svd.matrixU() * s * svd.matrixV().transpose();
  alignment.translation() = to_mean - alignment.linear() * from_mean;
  return alignment;
}

}  // namespace

DeltaUnit deltaUnitFromString(const std::string& text) {
  if (text == "s") return DeltaUnit::kSeconds;
  if (text == "f") return DeltaUnit::kFrames;
  if (text == "m") return DeltaUnit::kMeters;
  if (text == "rad") return DeltaUnit::kRadians;
  if (text == "deg") return DeltaUnit::kDegrees;
  throw std::invalid_argument("unknown delta unit '" + text + "' (expected s, f, m, rad or deg)");
}

std::string toString(DeltaUnit unit) {
  switch (unit) {
    case DeltaUnit::kSeconds:
      return "s";
    case DeltaUnit::kFrames:
      return "f";
    case DeltaUnit::kMeters:
      return "m";
    case DeltaUnit::kRadians:
      return "rad";
    case DeltaUnit::kDegrees:
      return "deg";
  }
  return "?";
}

ErrorStats errorStats(std::vector<double> values) {
  ErrorStats s;
  s.count = values.size();
  if (values.empty()) return s;
  const double n = static_cast<double>(values.size());
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double squares = 0.0, deviations = 0.0;
  for (const double v : values) {
    squares += v * v;
    deviations += (v - s.mean) * (v - s.mean);
  }
  s.rmse = std::sqrt(squares / n);
  s.std = std::sqrt(deviations / n);
  s.median = median(values);
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  s.min = *lo;
  s.max = *hi;
  return s;
}

RpeResult computeRpe(const Trajectory& groundtruth, const Trajectory& estimate, double delta,
                     DeltaUnit unit, double offset) {
  const Trajectory gt = byStamp(groundtruth), est = byStamp(estimate);
  if (gt.size() < 2 || est.size() < 2) {
    throw std::runtime_error("RPE needs at least two poses in each trajectory (ground truth has " +
                             std::to_string(gt.size()) + ", estimate " +
                             std::to_string(est.size()) + ")");
  }
  const std::vector<double> gt_stamps = stampsOf(gt);
  std::vector<double> est_stamps = stampsOf(est);
  for (double& t : est_stamps) t += offset;

  // A pose farther than twice the usual ground-truth interval from any ground truth is unmatched.
  const double max_time_difference = 2.0 * medianInterval(gt_stamps);

  const std::vector<double> index = deltaIndex(est, unit);
  std::vector<double> trans, rot;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const std::size_t j = findClosestIndex(index, index[i] + delta);
    if (j == est.size() - 1) continue;
    const std::size_t g0 = findClosestIndex(gt_stamps, est_stamps[i]);
    const std::size_t g1 = findClosestIndex(gt_stamps, est_stamps[j]);
    if (std::abs(gt_stamps[g0] - est_stamps[i]) > max_time_difference ||
        std::abs(gt_stamps[g1] - est_stamps[j]) > max_time_difference) {
      continue;
    }
    const Eigen::Isometry3d estimate_motion = est[i].pose.inverse() * est[j].pose;
    const Eigen::Isometry3d true_motion = gt[g0].pose.inverse() * gt[g1].pose;
    const Eigen::Isometry3d error = estimate_motion * true_motion.inverse();
    trans.push_back(error.translation().norm());
    rot.push_back(rotationAngle(error.linear()) * 180.0 / M_PI);
  }
  if (trans.size() < 2) {
    throw std::runtime_error("RPE: " + std::to_string(trans.size()) +
                             " pose pairs match ground truth (at least 2 needed); are the stamps "
                             "from the same sequence?");
  }
  RpeResult result;
  result.pairs = trans.size();
  result.trans = errorStats(std::move(trans));
  result.rot_deg = errorStats(std::move(rot));
  return result;
}

AteResult computeAte(const Trajectory& groundtruth, const Trajectory& estimate,
                     double max_difference, double offset) {
  AteResult result;
  const std::vector<std::size_t> gt_index = uniqueByStamp(groundtruth);
  const std::vector<std::size_t> est_index = uniqueByStamp(estimate);
  std::vector<double> gt_stamps, est_stamps;
  for (const std::size_t k : gt_index) gt_stamps.push_back(groundtruth[k].stamp);
  for (const std::size_t k : est_index) est_stamps.push_back(estimate[k].stamp + offset);
  for (const auto& [g, e] : detail::associateStamps(gt_stamps, est_stamps, max_difference)) {
    result.matches.emplace_back(gt_index[g], est_index[e]);
  }
  const std::size_t n = result.matches.size();
  if (n < 2) {
    throw std::runtime_error("ATE: " + std::to_string(n) + " estimate stamps are within " +
                             std::to_string(max_difference) +
                             " s of a ground-truth stamp (at least 2 needed)");
  }
  Eigen::Matrix3Xd est_points(3, n), gt_points(3, n);
  for (std::size_t k = 0; k < n; ++k) {
    gt_points.col(k) = groundtruth[result.matches[k].first].pose.translation();
    est_points.col(k) = estimate[result.matches[k].second].pose.translation();
  }
  result.alignment = hornAlignment(est_points, gt_points);
  std::vector<double> residuals(n);
  for (std::size_t k = 0; k < n; ++k) {
    residuals[k] =
        (result.alignment * Eigen::Vector3d(est_points.col(k)) - gt_points.col(k)).norm();
  }
  result.pairs = n;
  result.trans = errorStats(std::move(residuals));
  return result;
}

namespace {

constexpr double kOffsetStep = 5e-4;        // s, the search's grid
constexpr std::size_t kMinTurns = 10;       // turns compared, at least
constexpr double kObservableRise = 1.05;    // the curve's ends over its least value, at least
constexpr double kReferenceRateRatio = 0.5;  // the reference's interval over the frames', at most

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

}  // namespace

ClockOffset estimateClockOffset(const Trajectory& groundtruth,
                                const std::vector<Trajectory>& estimates, double max_offset) {
  Reference ref;
  ref.poses = byStamp(groundtruth);
  if (ref.poses.size() < 2) {
    throw std::runtime_error("clock offset: the reference has fewer than 2 poses");
  }
  ref.stamps = stampsOf(ref.poses);
  ref.interval = medianInterval(ref.stamps);
  const int half = int(std::lround(max_offset / kOffsetStep));
  if (half < 1) throw std::runtime_error("clock offset: the search range is below its step");

  // Between a reference's samples its turn is an interpolation: sampled no faster than the
  // frames, the offset found would be the one at which the interpolation smooths best.
  std::vector<Trajectory> sorted;
  for (const Trajectory& trajectory : estimates) {
    sorted.push_back(byStamp(trajectory));
    const double frame_interval = medianInterval(stampsOf(sorted.back()));
    if (sorted.back().size() > 2 && !(ref.interval <= kReferenceRateRatio * frame_interval)) {
      throw std::runtime_error(
          "clock offset: the reference is sampled every " + std::to_string(ref.interval) +
          " s, not at least twice as often as the frames (every " +
          std::to_string(frame_interval) + " s): its clock cannot be told from its frames'");
    }
  }

  ClockOffset result;
  std::vector<double> total(2 * std::size_t(half) + 1, 0.0);
  std::size_t contributing = 0;
  for (const Trajectory& est : sorted) {
    std::size_t turns = 0;
    const std::vector<double> sum = turnErrorCurve(ref, est, half, turns);
    result.turns += turns;
    const double least = *std::min_element(sum.begin(), sum.end());
    if (turns == 0 || !(least > 0.0)) continue;  // nothing to compare, or a copy of the reference
    for (std::size_t g = 0; g < total.size(); ++g) total[g] += sum[g] / least;
    ++contributing;
  }
  if (result.turns < kMinTurns || contributing == 0) {
    throw std::runtime_error("clock offset: " + std::to_string(result.turns) +
                             " frame-to-frame turns are covered by the reference at every offset "
                             "within +-" + std::to_string(max_offset) + " s (at least " +
                             std::to_string(kMinTurns) + " needed)");
  }
  result.offset = bestOffset(total, half, max_offset);
  // Each estimate's turn error at 0 and at the offset found, over the turns the reference
  // covers at both.
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
  return result;
}

}  // namespace acvo
