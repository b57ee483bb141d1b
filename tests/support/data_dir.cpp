#include "tests/support/data_dir.hpp"

#include <unistd.h>

#include <cstdlib>
#include <stdexcept>

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

std::filesystem::path temp_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() /
           ("livod-test-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

}  // namespace livod::test
