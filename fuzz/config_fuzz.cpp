// libFuzzer target: arbitrary bytes as a livod configuration file. load_config_from_string must
// never throw (yaml-cpp exceptions included) nor crash, and its result must be consistent: every
// problem formats to one line, and ok() means "no error".

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "daemon/config/load_config.hpp"
#include "daemon/config/summary.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // A base folder that does not exist: relative paths in the input resolve to nothing on disk.
  const auto result =
      livod::daemon::load_config_from_string(text, "fuzz.yaml", "/nonexistent-livod-fuzz");
  std::size_t errors = 0;
  for (const auto& problem : result.problems) {
    const std::string line = livod::daemon::format_problem(result.source, problem);
    if (line.empty() || problem.message.empty()) __builtin_trap();
    if (problem.severity == livod::daemon::Severity::error) ++errors;
  }
  if (result.ok() != (errors == 0)) __builtin_trap();
  if (result.ok()) {
    // What check-config prints for a valid file must also hold up.
    if (livod::daemon::summarize_config(result.config).empty()) __builtin_trap();
  }
  return 0;
}
