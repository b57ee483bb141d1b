// `livod version`: the version, how this binary was built (compiler, build type, flags,
// sanitizers, source revision at configure time: daemon/CMakeLists.txt) and what it was built
// with (library versions, the LiDAR families and their models).

#include <fmt/core.h>
#include <pcap/pcap.h>
#include <spdlog/version.h>
#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include <string>

#include "daemon/commands/command.hpp"
#include "drivers/lidar_family.hpp"

namespace livod::daemon {
namespace {

std::string or_unknown(const char* text) {
  return text[0] == '\0' ? std::string("unknown") : std::string(text);
}

}  // namespace

void add_version_command(CLI::App& app, CommandContext& ctx) {
  auto* cmd = app.add_subcommand("version", "Print the livod version and build settings");
  cmd->callback([&ctx] {
    fmt::print("livod {}\n", LIVOD_VERSION);
    fmt::print("revision    {}\n", or_unknown(LIVOD_GIT_REVISION));
    fmt::print("compiler    {}, C++{}\n", LIVOD_COMPILER, LIVOD_CXX_STANDARD);
    fmt::print("build type  {}\n", or_unknown(LIVOD_BUILD_TYPE));
    fmt::print("flags       {}\n", or_unknown(LIVOD_CXX_FLAGS));
    fmt::print("sanitizers  {}\n", LIVOD_SANITIZERS[0] == '\0' ? "none" : LIVOD_SANITIZERS);
    fmt::print(
        "libraries   Eigen {}.{}.{}, fmt {}.{}.{}, spdlog {}.{}.{}, yaml-cpp {}, OpenCV {}, {}\n",
        EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION, FMT_VERSION / 10000,
        FMT_VERSION / 100 % 100, FMT_VERSION % 100, SPDLOG_VER_MAJOR, SPDLOG_VER_MINOR,
        SPDLOG_VER_PATCH, or_unknown(LIVOD_YAML_CPP_VERSION), or_unknown(LIVOD_OPENCV_VERSION),
        pcap_lib_version());
    for (const drivers::LidarFamily* family : drivers::lidar_families()) {
      fmt::print("lidar       {:<11} {}\n", family->driver, family->model_list());
    }
    ctx.exit_code = 0;
  });
}

}  // namespace livod::daemon
