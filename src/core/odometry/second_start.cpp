// The second starts of a registration (second_start.hpp).
#include "acvo/odometry/second_start.hpp"

#include <algorithm>
#include <cmath>

#include "acvo/odometry/agreement.hpp"
#include "acvo/odometry/tracking.hpp"
#include "acvo/timing.hpp"

namespace acvo {
namespace {

// A second start's cost added to the first's: the frame's cost is both starts', whichever is kept.
void addStartCost(SolverResult& first, const SolverResult& again) {
  first.ms_total += again.ms_total;
  first.ms_neighbours += again.ms_neighbours;
  first.iterations += again.iterations;
}

// `again` replaces `first`, with the cost of both (already summed into `first`).
void keep(SolverResult& first, SolverResult again, StartOutcome& outcome) {
  outcome.kept = true;
  again.iterations = first.iterations;
  again.ms_total = first.ms_total;
  again.ms_neighbours = first.ms_neighbours;
  first = std::move(again);
}

}  // namespace

SolverResult SecondStart::apply(const StartContext& c, SolverResult first,
                                StartOutcome& outcome) const {
  if (!params_.second_start) return first;
  // A kept start from the rest of the points has already chosen between two maxima by the
  // image's agreement, which the kernel values fromGuess compares cannot tell apart there.
  if (c.facts.motion_unknown && params_.rest_start && restStart(c, first, outcome)) {
    outcome.pulled = true;
    return first;
  }
  fromGuess(c, first, outcome);
  return first;
}

void SecondStart::tracked(double stamp, double objective, bool pulled) {
  last_objective_ = objective;
  if (pulled) kept_at_ = stamp;
}

void SecondStart::forget() {
  kept_at_.reset();
  last_objective_.reset();
}

SolverResult SecondStart::finestFrom(const StartContext& c, SolverResult& first,
                                     const Eigen::Isometry3d& start,
                                     StartOutcome& outcome) const {
  outcome.ran = true;
  SolverResult again = c.engine.align(c.reference, c.moving, start, AlignStages::kFinest);
  addStartCost(first, again);
  return again;
}

bool SecondStart::restStart(const StartContext& c, SolverResult& first,
                            StartOutcome& outcome) const {
  if (failed(first.status)) return false;
  const auto t0 = Clock::now();
  const LabelledCloud& fixed = c.reference.cloud;
  const LabelledCloud& moving = c.moving.cloud;
  LabelledCloud rest = disagreeingPoints(fixed, moving, first.transform);
  if (!(double(rest.size()) > kRestFraction * double(moving.size())) ||
      int(rest.size()) < c.engine.minPoints()) {
    return false;
  }
  outcome.ran = true;
  const std::shared_ptr<PreparedCloud> alone = c.engine.prepare(std::move(rest), false);
  SolverResult again = c.engine.align(c.reference, *alone, c.guess);
  if (!failed(again.status)) {
    again = combinedStages(
        again, c.engine.align(c.reference, c.moving, again.transform, AlignStages::kFinest));
  }
  const bool better = !failed(again.status) &&
                      denseAgreement(fixed, moving, again.transform) >
                          kRestMargin * denseAgreement(fixed, moving, first.transform);
  // The registrations' own times, and the sorting, preparing and counting around them.
  again.ms_total = std::max(again.ms_total, msSince(t0));
  addStartCost(first, again);
  if (!better) return false;
  keep(first, std::move(again), outcome);
  return true;
}

bool SecondStart::turnStart(const StartContext& c, SolverResult& first,
                            StartOutcome& outcome) const {
  Eigen::Isometry3d start = first.transform;
  start.translation() = c.guess.translation();
  SolverResult again = finestFrom(c, first, start, outcome);
  if (failed(again.status) || !(again.objective > kSecondStartMargin * first.objective)) {
    return false;
  }
  keep(first, std::move(again), outcome);
  return true;
}

void SecondStart::fromGuess(const StartContext& c, SolverResult& first,
                            StartOutcome& outcome) const {
  if (failed(first.status)) return;
  // Both transforms map into the reference: guess^-1 T is the registered frame motion against
  // the guessed one, from any reference.
  const Eigen::Isometry3d missed = c.guess.inverse() * first.transform;
  const double miss_m = missed.translation().norm(), miss_deg = rotationDeg(missed);
  // A velocity change misses by its acceleration times the interval squared.
  const double frames = c.facts.interval / kSecondStartInterval;
  const double scale = std::max(1.0, frames * frames);
  const bool moved_off = miss_m > scale * kSecondStartTranslation;
  const bool turned_off = miss_deg > scale * kSecondStartRotation;
  const bool jerk = moved_off || turned_off;
  // A low kernel value against the last frame's says the first start ended in a wrong maximum.
  const bool scored_low =
      last_objective_ && first.objective < kTurnStartScoreShare * *last_objective_;
  if (params_.turn_start && moved_off && turned_off && scored_low && turnStart(c, first, outcome)) {
    return;  // kept for the image's ambiguity, not for a pull: not remembered
  }
  if (!jerk) {
    // The guess's usual miss: the camera's velocity changes between the last tracked frames over
    // this interval. An identity guess or one given from outside has no such measure. The
    // sigmas grow with the interval, the floors with its square.
    if (!params_.second_start_check || !c.facts.predicted) return;
    const Matrix6d& change = c.facts.velocity_changes;
    const double usual_m = std::sqrt(change.block<3, 3>(3, 3).trace()) * c.facts.interval;
    const double usual_deg =
        std::sqrt(change.block<3, 3>(0, 0).trace()) * c.facts.interval * 180.0 / M_PI;
    const double check_m =
        std::max(scale * kSecondStartCheckTranslation, kSecondStartCheckSigmas * usual_m);
    const double check_deg =
        std::max(scale * kSecondStartCheckRotation, kSecondStartCheckSigmas * usual_deg);
    if (miss_m <= check_m && miss_deg <= check_deg) return;
  }
  SolverResult again = finestFrom(c, first, c.guess, outcome);
  if (failed(again.status)) return;
  const bool pulled_lately = params_.second_start_memory && kept_at_ && c.facts.stamp >= *kept_at_ &&
                             c.facts.stamp - *kept_at_ <= kSecondStartMemory;
  if (jerk || pulled_lately) {
    // Beyond what the camera's own acceleration does, or soon after something pulled: the
    // guess's maximum, unless the other clearly scores higher.
    const double margin = pulled_lately ? kSecondStartKeptMargin : kSecondStartMargin;
    if (!(margin * again.objective > first.objective)) return;
  } else if (!(again.objective > kSecondStartCheckMargin * first.objective)) {
    return;  // within it the guess has no precedence and must clearly score higher
  }
  keep(first, std::move(again), outcome);
  outcome.pulled = true;
}

}  // namespace acvo
