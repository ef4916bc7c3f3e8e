// Throttling of warnings per cause rather than per call site. With one shared throttle a
// frequent cause takes every slot and a rarer one is never logged (the nodelet soak: of four
// kinds of bad frame injected in turn, camera_info with a zero focal length was not logged once
// in 10,000 frames). A cause is the message with its numbers blanked, so "truncated data: 1000
// bytes ..." and "truncated data: 2000 bytes ..." are one cause.
#pragma once

#include <cctype>
#include <cstddef>
#include <map>
#include <string>

namespace acvo_ros {

// The message with every run of digits replaced by one '#'.
inline std::string causeOf(const std::string& message) {
  std::string cause;
  cause.reserve(message.size());
  for (std::size_t k = 0; k < message.size(); ++k) {
    if (std::isdigit(static_cast<unsigned char>(message[k]))) {
      if (cause.empty() || cause.back() != '#') cause += '#';
    } else {
      cause += message[k];
    }
  }
  return cause;
}

class CauseThrottle {
 public:
  // At most max_causes causes are told apart; further ones (the message can carry names taken
  // from the input, e.g. an encoding) share one slot, so the memory stays bounded.
  explicit CauseThrottle(double period_s, std::size_t max_causes = 32)
      : period_(period_s), max_causes_(max_causes) {}

  // True when `message`'s cause was not let through in the last period_s (now_s counts as
  // its last time then).
  bool allow(const std::string& message, double now_s) {
    std::string cause = causeOf(message);
    if (last_.count(cause) == 0 && last_.size() >= max_causes_) cause = kOther;
    const auto it = last_.find(cause);
    if (it != last_.end() && now_s - it->second < period_) return false;
    last_[cause] = now_s;
    return true;
  }

 private:
  static constexpr const char* kOther = "";
  double period_;
  std::size_t max_causes_;
  std::map<std::string, double> last_;  // cause -> last time let through (s)
};

}  // namespace acvo_ros
