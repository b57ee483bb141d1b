// LatencyHistogram: percentiles within one bin of the exact nearest-rank value.

#include "daemon/runtime/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace livod::daemon::runtime {
namespace {

double exact(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}

TEST(LatencyHistogram, PercentilesWithinABin) {
  std::mt19937 rng(3);
  std::lognormal_distribution<double> dist(0.5, 1.0);  // ms: mostly 0.3..10, a tail beyond 20
  LatencyHistogram h;
  std::vector<double> values;
  for (int i = 0; i < 20000; ++i) {
    const double v = dist(rng);
    values.push_back(v);
    h.add(v);
  }
  EXPECT_EQ(h.count(), values.size());
  for (const double q : {0.5, 0.9, 0.99, 0.999}) {
    const double e = exact(values, q);
    const double bin = e < 20.0 ? 0.02 : 1.0;
    EXPECT_GE(h.percentile(q), e - 1e-12) << q;
    EXPECT_LE(h.percentile(q), e + bin) << q;
  }
  EXPECT_DOUBLE_EQ(h.max(), *std::max_element(values.begin(), values.end()));
}

TEST(LatencyHistogram, EdgesAndClear) {
  LatencyHistogram h;
  EXPECT_EQ(h.percentile(0.5), 0.0);
  h.add(-3.0);          // a clock step: counted as 0
  h.add(std::nan(""));  // counted as 0
  h.add(5000.0);        // beyond the last bin: the max is kept
  EXPECT_EQ(h.count(), 3U);
  EXPECT_DOUBLE_EQ(h.percentile(0.5), 0.02);
  EXPECT_DOUBLE_EQ(h.percentile(1.0), 5000.0);
  h.clear();
  EXPECT_EQ(h.count(), 0U);
  EXPECT_EQ(h.max(), 0.0);
}

}  // namespace
}  // namespace livod::daemon::runtime
