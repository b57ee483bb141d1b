// outputs.map_saves and the command channels: defaults, values read, a folder that does not exist
// (a warning: systemd may create it), a path that is a file (an error), unknown keys, a command
// channel that collides with another channel.

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "daemon/config/load_config.hpp"
#include "daemon/config/tests/config_test_support.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

using test::dump;
using test::find_problem;
using test::load;
using test::minimal_config;

// The minimal configuration followed by `yaml`. Appended as a std::string of run-time length: GCC
// 12 inlines `minimal_config() + "long literal"` here into a memcpy it then reports as out of
// bounds (a bogus -Warray-bounds, GCC bug 105651; it appeared with the tests' precompiled header).
std::string minimal_config_and(const std::string& yaml) {
  std::string config = minimal_config();
  config.append(yaml);
  return config;
}

TEST(ConfigMapSaves, Defaults) {
  const auto r = load(minimal_config());
  ASSERT_TRUE(r.ok()) << dump(r);
  const auto& s = r.config.outputs.map_saves;
  EXPECT_TRUE(s.enabled);
  EXPECT_TRUE(s.directory.empty());
  EXPECT_FALSE(s.overwrite);
  EXPECT_FALSE(s.at_stop);
  EXPECT_EQ(r.config.outputs.lcm.channels.command, "LIVOD_COMMAND");
  EXPECT_EQ(r.config.outputs.lcm.channels.command_result, "LIVOD_COMMAND_RESULT");
}

TEST(ConfigMapSaves, ValuesAreReadAndFoldersChecked) {
  const auto dir = livod::test::temp_dir("config-map-saves");
  {
    const auto r = load(minimal_config_and("outputs:\n  map_saves: {enabled: false, directory: " +
                                           dir.string() + ", overwrite: true, at_stop: true}\n"));
    ASSERT_TRUE(r.ok()) << dump(r);
    EXPECT_TRUE(r.problems.empty()) << dump(r);
    const auto& s = r.config.outputs.map_saves;
    EXPECT_FALSE(s.enabled);
    EXPECT_EQ(s.directory, dir);
    EXPECT_TRUE(s.overwrite);
    EXPECT_TRUE(s.at_stop);
  }
  {
    const auto r = load(minimal_config_and(
        "outputs:\n  map_saves: {directory: " + (dir / "nope").string() + "}\n"));
    EXPECT_TRUE(r.ok()) << dump(r);
    EXPECT_NE(find_problem(r, ProblemKind::missing_file, "outputs.map_saves.directory"), nullptr)
        << dump(r);
  }
  {
    std::ofstream(dir / "file") << "x";
    const auto r = load(minimal_config_and(
        "outputs:\n  map_saves: {directory: " + (dir / "file").string() + ", overwirte: true}\n"));
    EXPECT_FALSE(r.ok());
    EXPECT_NE(find_problem(r, ProblemKind::invalid_value, "outputs.map_saves.directory"), nullptr)
        << dump(r);
    EXPECT_NE(find_problem(r, ProblemKind::unknown_key, "outputs.map_saves.overwirte"), nullptr)
        << dump(r);
  }
}

TEST(ConfigMapSaves, CommandChannelMustNotShareAChannel) {
  const auto r = load(minimal_config_and("outputs:\n  lcm: {channels: {command: LIVOD_POSE}}\n"));
  EXPECT_FALSE(r.ok());
  EXPECT_NE(find_problem(r, ProblemKind::inconsistent, "outputs.lcm.channels.command"), nullptr)
      << dump(r);
}

}  // namespace
}  // namespace livod::daemon
