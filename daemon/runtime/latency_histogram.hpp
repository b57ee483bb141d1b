#pragma once
// A fixed-size histogram of durations (ms) with percentile queries: the daemon's latency and
// frame-time figures over hours in constant memory. Bins are 0.02 ms wide up to 20 ms, then
// 1 ms wide up to 1 s; larger values land in the last bin (and max() keeps the true maximum).

#include <array>
#include <cstddef>
#include <cstdint>

namespace livod::daemon::runtime {

class LatencyHistogram {
 public:
  void add(double ms);
  void clear();
  // Upper edge of the bin holding the q-quantile (nearest rank); 0 when empty.
  [[nodiscard]] double percentile(double q) const;
  [[nodiscard]] std::uint64_t count() const { return count_; }
  [[nodiscard]] double max() const { return max_; }
  [[nodiscard]] double mean() const {
    return count_ > 0 ? sum_ / static_cast<double>(count_) : 0.0;
  }

 private:
  static constexpr std::size_t kFineBins = 1000;   // 0.02 ms each: 0 .. 20 ms
  static constexpr std::size_t kCoarseBins = 980;  // 1 ms each: 20 ms .. 1 s
  static constexpr double kFineMs = 0.02;
  static constexpr double kFineEndMs = 20.0;
  std::array<std::uint32_t, kFineBins + kCoarseBins> bins_{};
  std::uint64_t count_ = 0;
  double sum_ = 0.0;
  double max_ = 0.0;
};

}  // namespace livod::daemon::runtime
