#pragma once
// Loading and validating the livod configuration file (docs/configuration.md).
//
// Never throws on bad user input: YAML syntax errors, unknown keys, wrong types, ranges and
// cross-sensor conflicts all become ConfigProblems, collected in one pass, each with its YAML
// path and line:column. Relative file paths in the file are resolved against the folder of the
// config file.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/problems.hpp"

namespace livod::daemon {

struct ConfigResult {
  LivodConfig config;
  std::vector<ConfigProblem> problems;  // sorted by position in the file
  std::string source;                   // the file name used in messages

  [[nodiscard]] std::size_t error_count() const;
  [[nodiscard]] std::size_t warning_count() const;
  // True when there is no error (warnings allowed): the daemon may start.
  [[nodiscard]] bool ok() const { return error_count() == 0; }
};

// Files larger than this are refused: a configuration is a few kilobytes, and the limit bounds
// the work done on garbage input.
constexpr std::size_t kMaxConfigBytes = 1024 * 1024;

ConfigResult load_config(const std::filesystem::path& path);

// `source_name` appears in messages; relative paths in the YAML are resolved against base_dir
// (the current directory when empty).
ConfigResult load_config_from_string(std::string_view yaml, std::string source_name,
                                     const std::filesystem::path& base_dir = {});

}  // namespace livod::daemon
