// The brightness between two images (docs/method.md §6): the gain of a camera's auto exposure
// and its lens's vignetting, measured from the grey values of the points the images share.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "acvo/math/order_statistics.hpp"
#include "acvo/registration/direct_terms.hpp"

namespace acvo {

Brightness brightnessOf(const std::vector<GreyPair>& pairs, bool gain, bool vignetting) {
  struct Usable {
    double log_ratio, shift, flat;
  };
  std::vector<Usable> usable;
  usable.reserve(pairs.size());
  const std::size_t stride =
      std::max<std::size_t>(1, (pairs.size() + kBrightnessPairs - 1) / kBrightnessPairs);
  for (std::size_t k = 0; k < pairs.size(); k += stride) {
    const GreyPair& p = pairs[k];
    if (p.reference < kSaturated && p.moving < kSaturated && p.reference >= kDark &&
        p.moving >= kDark) {
      usable.push_back({std::log(double(p.reference) / double(p.moving)), p.shift, p.flat});
    }
  }
  if (usable.size() < kMinGainPairs || !(gain || vignetting)) return {};
  // The lower median of log(ratio) - v shift (weightedMedian's answer for equal weights).
  std::vector<double> rest(usable.size());
  auto logGain = [&](double v) {
    for (std::size_t k = 0; k < usable.size(); ++k) {
      rest[k] = usable[k].log_ratio - v * usable[k].shift;
    }
    return kthSmallest(rest.data(), rest.data() + rest.size(), (rest.size() - 1) / 2);
  };
  Brightness b;
  double log_gain = gain ? logGain(0.0) : 0.0;
  if (vignetting) {
    std::vector<std::pair<double, double>> slopes;  // (slope, weight)
    slopes.reserve(usable.size());
    for (int round = 0; round < kBrightnessRounds; ++round) {
      slopes.clear();
      for (const Usable& u : usable) {
        if (std::abs(u.shift) > 1e-6) {
          slopes.emplace_back((u.log_ratio - log_gain) / u.shift, std::abs(u.shift) * u.flat);
        }
      }
      if (slopes.size() < kMinGainPairs) break;
      b.vignetting = std::clamp(weightedMedian(slopes), kMinVignetting, kMaxVignetting);
      if (gain) log_gain = logGain(b.vignetting);
    }
  }
  b.gain = std::exp(log_gain);
  if (!(b.gain >= 1.0 / kMaxGain && b.gain <= kMaxGain)) return {};
  return b;
}

}  // namespace acvo
