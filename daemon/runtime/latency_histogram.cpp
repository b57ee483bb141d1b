#include "daemon/runtime/latency_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace livod::daemon::runtime {

void LatencyHistogram::add(double ms) {
  if (!(ms >= 0.0)) ms = 0.0;  // NaN and negative (clock step) count as 0
  std::size_t bin = 0;
  if (ms < kFineEndMs) {
    bin = static_cast<std::size_t>(ms / kFineMs);
  } else {
    bin = kFineBins + static_cast<std::size_t>(ms - kFineEndMs);
  }
  bin = std::min(bin, bins_.size() - 1);
  ++bins_[bin];
  ++count_;
  sum_ += ms;
  max_ = std::max(max_, ms);
}

void LatencyHistogram::clear() {
  *this = LatencyHistogram{};
}

double LatencyHistogram::percentile(double q) const {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<std::uint64_t>(
      std::clamp(std::ceil(q * static_cast<double>(count_)), 1.0, static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < bins_.size(); ++i) {
    seen += bins_[i];
    if (seen >= rank) {
      if (i + 1 == bins_.size()) return max_;  // the overflow bin
      const double upper = i < kFineBins ? static_cast<double>(i + 1) * kFineMs
                                         : kFineEndMs + static_cast<double>(i - kFineBins + 1);
      return std::min(upper, max_);
    }
  }
  return max_;
}

}  // namespace livod::daemon::runtime
