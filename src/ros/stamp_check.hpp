// What to do with a frame given its stamp and the last processed one (seconds; last = 0 when
// there is none): the nodelet's rules for reordered, repeated and restarted streams.
#pragma once

namespace acvo_ros {

enum class StampVerdict {
  kAccept,   // later than the last one, within max_gap
  kGap,      // later, but by more than max_gap: warn and process
  kDrop,     // not later (repeated or slightly reordered): drop with a warning
  kRestart,  // earlier by more than jump_back (a bag restarted): reset odometry, then process
};

inline StampVerdict checkStamp(double last, double stamp, double max_gap, double jump_back = 1.0) {
  if (last == 0.0) return StampVerdict::kAccept;
  if (stamp <= last) return last - stamp > jump_back ? StampVerdict::kRestart : StampVerdict::kDrop;
  return stamp - last > max_gap ? StampVerdict::kGap : StampVerdict::kAccept;
}

}  // namespace acvo_ros
