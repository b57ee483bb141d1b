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

// A fresh empty directory under the system temp dir. Removed when the test process exits if every
// test passed; kept after a failure, or always with LIVOD_KEEP_TEST_DIRS=1, for inspection.
std::filesystem::path temp_dir(const std::string& name);

}  // namespace livod::test
