#include "tests/support/data_dir.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace livod::test {

std::filesystem::path source_dir() {
  // ctest passes it in the environment (like LIVOD_DATA_DIR); the compiled-in default serves a
  // test binary run by hand.
  if (const char* env = std::getenv("LIVOD_SOURCE_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  return LIVOD_SOURCE_DIR;
}

std::filesystem::path data_dir() {
  if (const char* env = std::getenv("LIVOD_DATA_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  return LIVOD_DEFAULT_DATA_DIR;
}

std::filesystem::path data_path(const std::string& relative) {
  auto p = data_dir() / relative;
  if (!std::filesystem::exists(p)) {
    throw std::runtime_error("test data missing: " + p.string() +
                             " (set LIVOD_DATA_DIR to the shared/data folder)");
  }
  return p;
}

namespace {

// The directories temp_dir() made in this process, removed when it exits unless a test failed
// (kept for inspection) or LIVOD_KEEP_TEST_DIRS is set: simulated captures take up to a GB each,
// and a developer's machine runs the suite many times a day.
class TempDirs {
 public:
  void add(const std::filesystem::path& p) {
    const std::lock_guard lock(mutex_);
    dirs_.push_back(p);
  }
  ~TempDirs() {
    const char* keep = std::getenv("LIVOD_KEEP_TEST_DIRS");
    if ((keep != nullptr && *keep != '\0') || ::testing::UnitTest::GetInstance()->Failed()) return;
    for (const auto& d : dirs_) {
      std::error_code ec;  // best effort: a directory in use stays
      std::filesystem::remove_all(d, ec);
    }
  }

 private:
  std::mutex mutex_;
  std::vector<std::filesystem::path> dirs_;
};

TempDirs& temp_dirs() {
  static TempDirs dirs;
  return dirs;
}

}  // namespace

std::filesystem::path temp_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() /
           ("livod-test-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  temp_dirs().add(p);
  return p;
}

}  // namespace livod::test
