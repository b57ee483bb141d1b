#pragma once
// Test support: reads the ATE line of `livod eval`'s report back, the way a script would.
// (std::regex is avoided: GCC 12 warns inside <regex> under the sanitizer builds.)

#include <cstddef>
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>

namespace livod::eval::test_support {

struct AteLine {
  double rmse_m = 0.0;
  double mean_m = 0.0;
  double max_m = 0.0;
  std::size_t poses = 0;
};

// The line "ATE  RMSE <m> m  mean <m> m  median <m> m  std <m> m  min <m> m  max <m> m  (<N>
// poses)", or nothing when no line of the report has exactly that shape.
inline std::optional<AteLine> parse_ate_line(const std::string& report) {
  std::istringstream lines(report);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("ATE  RMSE ", 0) != 0) continue;
    AteLine a;
    double median = 0.0;
    double std_dev = 0.0;
    double min = 0.0;
    int consumed = 0;
    const int n =
        std::sscanf(line.c_str(),
                    "ATE  RMSE %lf m  mean %lf m  median %lf m  std %lf m  min %lf m  "
                    "max %lf m  (%zu poses)%n",
                    &a.rmse_m, &a.mean_m, &median, &std_dev, &min, &a.max_m, &a.poses, &consumed);
    if (n == 7 && static_cast<std::size_t>(consumed) == line.size()) return a;
  }
  return std::nullopt;
}

}  // namespace livod::eval::test_support
