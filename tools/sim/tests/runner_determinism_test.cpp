// Same scenario, same seed: byte-identical output folders (every file, the bag included); another
// seed: another capture.

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <map>

#include "tests/support/data_dir.hpp"
#include "tools/sim/runner.hpp"

namespace livod::sim {
namespace {

// Relative path -> contents of every regular file under `dir`.
std::map<std::string, std::string> read_tree(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    files[std::filesystem::relative(entry.path(), dir).string()] =
        std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return files;
}

std::map<std::string, std::string> run(const std::string& name, std::uint64_t seed, double duration,
                                       bool images) {
  SimRunOptions o;
  o.out_dir = test::temp_dir(name);
  o.seed = seed;
  o.duration_s = duration;
  o.write_images = images;
  o.write_bag = true;
  run_scenario(make_scenario("room_handheld_avia"), o);
  return read_tree(o.out_dir);
}

void expect_identical(const std::map<std::string, std::string>& a,
                      const std::map<std::string, std::string>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [path, bytes] : a) {
    ASSERT_TRUE(b.contains(path)) << path;
    EXPECT_FALSE(bytes.empty()) << path;
    EXPECT_TRUE(bytes == b.at(path)) << path << " differs between two runs with the same seed";
  }
}

TEST(RunnerDeterminism, SameSeedGivesByteIdenticalFolders) {
  const auto a = run("determinism_a", 3, 1.5, false);
  const auto b = run("determinism_b", 3, 1.5, false);
  for (const char* f : {"avia.pcap", "groundtruth.txt", "config.yaml", "scenario.txt",
                        "sequence.bag", "mav0/cam0/data.csv", "mav0/cam0/sensor.yaml"}) {
    EXPECT_TRUE(a.contains(f)) << f;
  }
  expect_identical(a, b);

  const auto c = run("determinism_c", 4, 1.5, false);
  ASSERT_TRUE(c.contains("avia.pcap"));
  EXPECT_NE(a.at("avia.pcap"), c.at("avia.pcap")) << "the seed does not reach the capture";
  EXPECT_NE(a.at("sequence.bag"), c.at("sequence.bag"));
  // The trajectory is the scenario's, not the seed's.
  EXPECT_EQ(a.at("groundtruth.txt"), c.at("groundtruth.txt"));
}

TEST(RunnerDeterminism, SameSeedGivesByteIdenticalImages) {
  const auto a = run("determinism_images_a", 8, 0.3, true);
  const auto b = run("determinism_images_b", 8, 0.3, true);
  int pngs = 0;
  for (const auto& [path, _] : a) pngs += path.ends_with(".png") ? 1 : 0;
  EXPECT_EQ(pngs, 3);
  expect_identical(a, b);
  const auto c = run("determinism_images_c", 9, 0.3, true);
  for (const auto& [path, bytes] : a) {
    // Sensor noise and the room's furniture depend on the seed.
    if (path.ends_with(".png")) {
      EXPECT_NE(bytes, c.at(path)) << path;
    }
  }
}

}  // namespace
}  // namespace livod::sim
