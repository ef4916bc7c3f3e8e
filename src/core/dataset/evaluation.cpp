// RPE and ATE as the TUM RGB-D benchmark tools compute them (docs/method.md §8).
#include "acvo/dataset/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "stamp_association.hpp"
#include "trajectory_stamps.hpp"

namespace acvo {
namespace {

using detail::byStamp;
using detail::median;
using detail::medianInterval;
using detail::stampsOf;
using detail::uniqueByStamp;

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

}  // namespace acvo
