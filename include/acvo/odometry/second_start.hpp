// The second start (OdometryParams::second_start): where a registration's motion misses the
// motion guess, the finest level is run again from the guess, and the odometry keeps the
// maximum of the objective that the camera's own predicted motion leads to unless the first
// clearly scores higher. Something large moving in view (a person) can pull the coarse levels,
// whose wide kernel spans both motions, into its own motion; the finest level's narrow kernel,
// started from the camera's predicted motion, holds the still part of the view.
//  - A miss beyond a jerk (kSecondStartTranslation, kSecondStartRotation, grown with the
//    interval squared) runs it; it is kept unless the first scores kSecondStartMargin times
//    higher.
//  - A miss under those limits but unusual for this camera (kSecondStartCheckSigmas times its
//    recent velocity changes, at least the floors kSecondStartCheck*) runs it too, where the
//    guess is a constant-velocity prediction from a known velocity (second_start_check); there
//    the camera's own acceleration may be the cause, so it is kept only where it scores
//    kSecondStartCheckMargin times the first.
//  - Within kSecondStartMemory of a kept second start, the first must score
//    kSecondStartKeptMargin times the second's to be kept (second_start_memory): a person
//    filling more of the view can outscore the room.
//  - A turn and a translation that both miss, scoring under kTurnStartScoreShare of the last
//    frame's kernel value, are run again from the registered turn with the guess's translation
//    (turn_start): a small turn and a sideways move shift the image alike, and the coarse
//    levels' few points can take part of a fast turn for a move. Kept where it scores
//    kSecondStartMargin times the first.
//  - Where no motion is known yet (the first frame, the first after a lost one) and over
//    kRestFraction of the points disagree with the reference under the motion found
//    (agreement.hpp), those points are registered alone from the guess and the whole cloud
//    refined from their motion (rest_start); kept where kRestMargin times as many of the image's
//    pixels agree with it: the camera's motion is the one most of the view agrees with.
#pragma once

#include <optional>

#include <Eigen/Geometry>

#include "acvo/params.hpp"
#include "acvo/registration/engine.hpp"

namespace acvo {

// A velocity change of 0.6 m/s or 90 deg/s within a frame at 30 Hz: more than a hand-held
// camera's (its guess misses by up to 20 mm and 1.5 deg a frame on the real folders).
inline constexpr double kSecondStartTranslation = 0.02;     // m
inline constexpr double kSecondStartRotation = 3.0;         // deg
inline constexpr double kSecondStartInterval = 1.0 / 30.0;  // s: the limits' frame interval
// Of two maxima, the guess's unless the other scores this much higher.
inline constexpr double kSecondStartMargin = 1.2;
// After a kept second start, the first must score this much higher for this long.
inline constexpr double kSecondStartKeptMargin = 2.0;
inline constexpr double kSecondStartMemory = 0.25;  // s
// Under the limits: the guess's usual miss times this, and at least these floors.
inline constexpr double kSecondStartCheckSigmas = 3.0;
inline constexpr double kSecondStartCheckTranslation = 0.005;  // m
inline constexpr double kSecondStartCheckRotation = 0.75;      // deg
// ... and there the second start must score this much higher than the first.
inline constexpr double kSecondStartCheckMargin = 1.1;
// A first start under this share of the last frame's kernel value may be a turn taken for a move.
inline constexpr double kTurnStartScoreShare = 0.3;
// With no motion known: the share of disagreeing points that calls for a start from them, and
// how many more of the image's pixels must agree with its result for it to be kept.
inline constexpr double kRestFraction = 0.1;
inline constexpr double kRestMargin = 1.1;

// What the odometry knows of a frame's motion guess.
struct GuessFacts {
  double interval = 0.0;  // s since the last tracked frame
  double stamp = 0.0;     // this frame's
  // The guess is the constant-velocity prediction from a known velocity, and the camera's
  // recent velocity changes (VelocityChanges::moment) say how far such a guess usually misses.
  bool predicted = false;
  Matrix6d velocity_changes = Matrix6d::Zero();
  bool motion_unknown = false;  // the constant-velocity guess, while no motion is known
};

// The frame, its guess and its reference, as a second start sees them.
struct StartContext {
  const RegistrationEngine& engine;
  const PreparedCloud& reference;
  const PreparedCloud& moving;
  Eigen::Isometry3d guess;  // T: this frame -> the reference
  GuessFacts facts;
};

// What the second starts of one registration did.
struct StartOutcome {
  bool ran = false;     // a second start ran
  bool kept = false;    // ... and its result replaced the first's
  bool pulled = false;  // ... for a pull by something in view (it starts kSecondStartMemory)
};

// The second starts, with what they remember from frame to frame: when one was last kept for a
// pull, and the last tracked frame's kernel value.
class SecondStart {
 public:
  explicit SecondStart(const OdometryParams& params) : params_(params) {}

  // The registration to keep, the first one or a second start (whose cost, all starts', it
  // carries), and what ran in `outcome`. Runs nothing unless second_start is on.
  SolverResult apply(const StartContext& c, SolverResult first, StartOutcome& outcome) const;
  // After a tracked frame: its kernel value and whether it kept a second start for a pull.
  void tracked(double stamp, double objective, bool pulled);
  // After a lost frame or a reset: nothing to compare with.
  void forget();

 private:
  // The finest level again from `start`, its cost added to `first`'s.
  SolverResult finestFrom(const StartContext& c, SolverResult& first,
                          const Eigen::Isometry3d& start, StartOutcome& outcome) const;
  // The second start from the disagreeing points; whether it was kept (into `first`).
  bool restStart(const StartContext& c, SolverResult& first, StartOutcome& outcome) const;
  // The second start from the registered turn with the guess's translation, for a frame whose
  // turn and translation both missed and that scored low; whether it was kept.
  bool turnStart(const StartContext& c, SolverResult& first, StartOutcome& outcome) const;
  // The second start from the guess, on a jerk or an unusual miss.
  void fromGuess(const StartContext& c, SolverResult& first, StartOutcome& outcome) const;

  OdometryParams params_;
  std::optional<double> kept_at_;         // stamp of the last frame that kept one for a pull
  std::optional<double> last_objective_;  // the last tracked frame's kernel value
};

}  // namespace acvo
