// Every example configuration shipped in the repository loads without errors. The only
// acceptable warnings are replay recordings that are not part of the repository. The planned
// examples (docs/examples/planned/) fail, but only because a feature is not implemented yet.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <vector>

#include "daemon/config/load_config.hpp"
#include "daemon/config/tests/config_test_support.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

std::filesystem::path repository_root() {
  return livod::test::source_dir();
}

std::vector<std::filesystem::path> yaml_files(const std::vector<std::filesystem::path>& folders) {
  std::vector<std::filesystem::path> files;
  for (const auto& folder : folders) {
    if (!std::filesystem::is_directory(folder)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      const auto ext = entry.path().extension();
      if (entry.is_regular_file() && (ext == ".yaml" || ext == ".yml")) {
        files.push_back(entry.path());
      }
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::filesystem::path> example_configs() {
  const auto root = repository_root();
  return yaml_files({root / "systemd", root / "docs" / "examples"});
}

TEST(ConfigExamples, RepositoryHasExamples) {
  const auto files = example_configs();
  EXPECT_TRUE(std::filesystem::exists(repository_root() / "systemd" / "livod.example.yaml"))
      << repository_root();
  EXPECT_GE(files.size(), 3u);
}

TEST(ConfigExamples, EveryExampleLoadsWithoutErrors) {
  for (const auto& file : example_configs()) {
    SCOPED_TRACE(file.string());
    const auto result = load_config(file);
    EXPECT_EQ(result.error_count(), 0u) << test::dump(result);
    for (const auto& p : result.problems) {
      const bool missing_recording = p.kind == ProblemKind::missing_file &&
                                     p.path.find(".source.replay.file") != std::string::npos;
      EXPECT_TRUE(missing_recording) << format_problem(result.source, p);
    }
    EXPECT_FALSE(result.config.sensors.empty());
    EXPECT_GE(result.config.body_sensor_index, 0);
  }
}

TEST(ConfigExamples, PlannedExamplesFailOnlyForWhatIsNotImplemented) {
  const auto planned = yaml_files({repository_root() / "docs" / "examples" / "planned"});
  EXPECT_GE(planned.size(), 4u);
  for (const auto& file : planned) {
    SCOPED_TRACE(file.string());
    const auto result = load_config(file);
    EXPECT_GT(result.error_count(), 0u) << "implemented now? move it to docs/examples/";
    for (const auto& p : result.problems) {
      if (p.severity != Severity::error) continue;
      EXPECT_EQ(p.kind, ProblemKind::not_implemented) << format_problem(result.source, p);
    }
  }
}

// The systemd example is the reference robot config: it must be completely clean.
TEST(ConfigExamples, SystemdExampleIsClean) {
  const auto result = load_config(repository_root() / "systemd" / "livod.example.yaml");
  EXPECT_TRUE(result.problems.empty()) << test::dump(result);
  EXPECT_EQ(result.config.body_frame, "avia.imu");
  EXPECT_TRUE(result.config.body_is_internal_imu);
}

// The Ouster replay example points at the real capture of the shared data beside the repository.
TEST(ConfigExamples, OusterReplayExampleFindsTheSharedCapture) {
  const auto result =
      load_config(repository_root() / "docs" / "examples" / "ouster-os1-128-replay.yaml");
  ASSERT_TRUE(result.ok()) << test::dump(result);
  const auto& os1 = result.config.sensors.at(0);
  EXPECT_TRUE(std::filesystem::exists(os1.metadata)) << os1.metadata;
  // inverse of the metadata's imu_to_sensor_transform (mm -> m)
  EXPECT_TRUE(os1.T_body_sensor.translation().isApprox(
      Eigen::Vector3d(-0.006253, 0.011775, -0.007645), 1e-12));
}

}  // namespace
}  // namespace livod::daemon
