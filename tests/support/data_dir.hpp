#pragma once
// Where tests find the real recorded data (../shared/data). The environment variable
// LIVOD_DATA_DIR wins over the build-time default, so a test binary can be run from anywhere.

#include <filesystem>
#include <string>

namespace livod::test {

std::filesystem::path data_dir();

// The repository's root (the CMake source directory of the build): for tests that read the
// repository's own files (example configurations, scripts).
std::filesystem::path source_dir();

// data_dir() / relative; fails the current test (GTEST_SKIP is not used: missing data is an error).
std::filesystem::path data_path(const std::string& relative);

// A fresh empty directory under the system temp dir (left in place for inspection after a run).
std::filesystem::path temp_dir(const std::string& name);

}  // namespace livod::test
