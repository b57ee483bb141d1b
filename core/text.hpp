#pragma once
// Small text helpers shared by the line-based parsers (EuRoC csv, HTTP headers, ROS message
// definitions, Hesai calibration csv).

#include <string_view>

namespace livod {

// `s` without the whitespace at either end (space, tab, CR, LF, VT, FF: the C locale's isspace).
constexpr std::string_view trim_whitespace(std::string_view s) {
  constexpr std::string_view kWhitespace = " \t\r\n\v\f";
  const auto first = s.find_first_not_of(kWhitespace);
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(kWhitespace) - first + 1);
}

}  // namespace livod
