// What to do with a frame given its stamp and the stream so far: the nodelet's rules for
// reordered, repeated and restarted streams.
#pragma once

#include <optional>

namespace acvo_ros {

enum class StampVerdict {
  kAccept,   // later than the last one, within max_gap
  kGap,      // later, but by more than max_gap: warn and process
  kDrop,     // not later (repeated or slightly reordered): drop with a warning
  kRestart,  // the stream started again from an earlier time: restart, then process
};

// The rule for one stamp against the last processed one (seconds; last = 0 when there is none).
inline StampVerdict checkStamp(double last, double stamp, double max_gap, double jump_back = 1.0) {
  if (last == 0.0) return StampVerdict::kAccept;
  if (stamp <= last) return last - stamp > jump_back ? StampVerdict::kRestart : StampVerdict::kDrop;
  return stamp - last > max_gap ? StampVerdict::kGap : StampVerdict::kAccept;
}

// checkStamp over a stream, which also tells a restart that jumps back by less than jump_back
// (a looped bag shorter than that) from a frame out of order: a second frame in a row behind
// the last processed one, and later than the first, is a stream going on from an earlier time
// (two frames out of order would not be in order among themselves).
class StampGuard {
 public:
  StampVerdict check(double stamp, double max_gap, double jump_back) {
    StampVerdict v = checkStamp(last_, stamp, max_gap, jump_back);
    if (v == StampVerdict::kDrop && behind_ && stamp > *behind_) v = StampVerdict::kRestart;
    behind_ = v == StampVerdict::kDrop ? std::optional<double>(stamp) : std::nullopt;
    return v;
  }
  // A frame with this stamp was processed.
  void processed(double stamp) { last_ = stamp; }
  // Forget the stream (a restart): the next stamp is accepted.
  void clear() { *this = StampGuard(); }
  double last() const { return last_; }

 private:
  double last_ = 0.0;              // stamp of the last frame processed, 0 = none
  std::optional<double> behind_;   // the last frame dropped for being behind, if the one before
};

}  // namespace acvo_ros
