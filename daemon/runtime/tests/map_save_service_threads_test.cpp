// Map saves on request (runtime/map_save_service.hpp, map_saver.hpp): file names, atomic writes,
// overwrite mode, errors reported instead of thrown, commands answered, requests that arrive while
// a save runs coalesced into it, disabled saving rejected. The file content is compared with the
// map's points byte for byte here; tests/runtime/pcl_tests loads the files with PCL.
//
// Label "threads" (ThreadSanitizer in CI): the map writer thread reads the map while the test
// thread appends to it, and hands its outcome back.

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "daemon/replay/map_accumulator.hpp"
#include "daemon/runtime/map_save_service.hpp"
#include "daemon/runtime/publisher.hpp"
#include "drivers/capture/doorbell.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::runtime {
namespace {

using publish::CommandRecord;
using publish::CommandResultRecord;
using publish::CommandStatus;

// A bus that hands out queued commands and keeps the results.
class CommandBus final : public MessageBus {
 public:
  void publish_pose(const PoseRecord& /*pose*/) override {}
  void publish_health(const HealthRecord& /*health*/) override {}
  void publish_cloud(const publish::CloudRecord& /*cloud*/) override {}
  [[nodiscard]] std::uint64_t failures() const override { return 0; }
  void poll_commands(std::vector<CommandRecord>& out) override {
    out.insert(out.end(), queued.begin(), queued.end());
    queued.clear();
  }
  void publish_command_result(const CommandResultRecord& r) override { results.push_back(r); }

  std::vector<CommandRecord> queued;
  std::vector<CommandResultRecord> results;
};

CommandRecord save_command(std::int64_t id, std::string sender = "test") {
  CommandRecord c;
  c.request_id = id;
  c.sender = std::move(sender);
  c.command = static_cast<std::int8_t>(publish::Command::kSaveMap);
  return c;
}

replay::MapAccumulator random_map(std::size_t n, unsigned seed) {
  replay::MapAccumulator map(0.05, 1'000'000);
  map.reserve_budget();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  while (map.size() < n) map.add(Eigen::Vector3d(u(rng), u(rng), u(rng)));
  return map;
}

// The points of a binary x y z PCD (checks the header's fields and count).
std::vector<float> read_pcd_points(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t points = 0;
  bool fields_ok = false;
  while (std::getline(in, line)) {
    if (line == "FIELDS x y z") fields_ok = true;
    if (line.rfind("POINTS ", 0) == 0) points = std::stoul(line.substr(7));
    if (line == "DATA binary") break;
  }
  EXPECT_TRUE(fields_ok) << path;
  std::vector<float> xyz(3 * points);
  in.read(reinterpret_cast<char*>(xyz.data()), static_cast<std::streamsize>(xyz.size() * 4));
  EXPECT_EQ(in.gcount(), static_cast<std::streamsize>(xyz.size() * 4)) << path;
  EXPECT_EQ(in.peek(), EOF) << "bytes after the points in " << path;
  return xyz;
}

std::vector<std::filesystem::path> files_in(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// Turns the service until `results` has `n` entries (the writer thread finishing).
void turn_until(MapSaveService& service, const replay::MapAccumulator* map, CommandBus& bus,
                std::size_t n) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (bus.results.size() < n && std::chrono::steady_clock::now() < deadline) {
    service.turn(map, &bus);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_GE(bus.results.size(), n) << "no answer within 30 s";
}

TEST(MapFileName, UtcTimeAndNumber) {
  // 2026-11-26 06:11:05 UTC
  EXPECT_EQ(map_file_name(1'795'673'465'123'000'000, 3), "map-20261126T061105Z-0003.pcd");
}

TEST(MapSaveService, CommandsAnsweredWithNumberedFilesThatHoldTheMap) {
  const auto dir = test::temp_dir("mapsave-numbered");
  drivers::capture::Doorbell wake;
  MapSaveServiceOptions o;
  o.enabled = true;
  o.saver.directory = dir;
  MapSaveService service(o, wake);
  CommandBus bus;
  auto map = random_map(20'000, 1);

  bus.queued.push_back(save_command(41, "laptop"));
  turn_until(service, &map, bus, 1);
  // The map grows between saves: the second file holds more points, the first is untouched.
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(60.0, 90.0);
  while (map.size() < 30'000) map.add(Eigen::Vector3d(u(rng), u(rng), u(rng)));
  bus.queued.push_back(save_command(42, "laptop"));
  turn_until(service, &map, bus, 2);

  ASSERT_EQ(bus.results.size(), 2U);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& r = bus.results[i];
    EXPECT_EQ(r.status, CommandStatus::kOk) << r.message;
    EXPECT_EQ(r.request_id, 41 + static_cast<std::int64_t>(i));
    EXPECT_EQ(r.requested_by, "laptop");
    EXPECT_FALSE(r.coalesced);
    EXPECT_EQ(r.save_number, static_cast<int>(i) + 1);
    EXPECT_EQ(std::filesystem::path(r.path).parent_path(), std::filesystem::absolute(dir));
    EXPECT_EQ(static_cast<std::uintmax_t>(r.bytes), std::filesystem::file_size(r.path));
    EXPECT_GT(r.snapshot_unix_ns, 1'700'000'000'000'000'000);
  }
  EXPECT_EQ(bus.results[0].points, 20'000);
  EXPECT_EQ(bus.results[1].points, 30'000);
  EXPECT_NE(bus.results[0].path, bus.results[1].path);
  // Only the two finished files: no partial file left behind.
  EXPECT_EQ(files_in(dir).size(), 2U);
  const auto first = read_pcd_points(bus.results[0].path);
  const auto second = read_pcd_points(bus.results[1].path);
  ASSERT_EQ(first.size(), 3U * 20'000);
  ASSERT_EQ(second.size(), 3U * 30'000);
  EXPECT_EQ(std::memcmp(first.data(), map.xyz().data(), first.size() * 4), 0);
  EXPECT_EQ(std::memcmp(second.data(), map.xyz().data(), second.size() * 4), 0);
  EXPECT_EQ(service.stats().saved, 2U);
}

TEST(MapSaveService, OverwriteReplacesOneFile) {
  const auto dir = test::temp_dir("mapsave-overwrite");
  drivers::capture::Doorbell wake;
  MapSaveServiceOptions o;
  o.enabled = true;
  o.saver.directory = dir;
  o.saver.overwrite = true;
  MapSaveService service(o, wake);
  CommandBus bus;
  auto small = random_map(1'000, 3);
  auto big = random_map(5'000, 4);
  bus.queued.push_back(save_command(1));
  turn_until(service, &small, bus, 1);
  bus.queued.push_back(save_command(2));
  turn_until(service, &big, bus, 2);
  EXPECT_EQ(bus.results[0].path, (std::filesystem::absolute(dir) / "map.pcd").string());
  EXPECT_EQ(bus.results[1].path, bus.results[0].path);
  EXPECT_EQ(files_in(dir).size(), 1U);
  EXPECT_EQ(read_pcd_points(dir / "map.pcd").size(), 3U * 5'000);
}

TEST(MapSaveService, RequestsDuringASaveJoinItAndAreAllAnswered) {
  const auto dir = test::temp_dir("mapsave-coalesce");
  drivers::capture::Doorbell wake;
  // The writer thread waits in the hook until released: the save stays in progress.
  std::mutex m;
  std::condition_variable cv;
  bool released = false;
  bool writing = false;
  MapSaveServiceOptions o;
  o.enabled = true;
  o.saver.directory = dir;
  o.saver.before_write = [&] {
    std::unique_lock lock(m);
    writing = true;
    cv.notify_all();
    cv.wait(lock, [&] { return released; });
  };
  MapSaveService service(o, wake);
  CommandBus bus;
  auto map = random_map(10'000, 5);

  bus.queued.push_back(save_command(7, "a"));
  service.turn(&map, &bus);
  {
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return writing; });
  }
  // While it writes: a signal and another command arrive, and the map grows.
  service.request_from_signal();
  bus.queued.push_back(save_command(8, "b"));
  map.add(Eigen::Vector3d(100.0, 100.0, 100.0));
  service.turn(&map, &bus);
  service.turn(&map, &bus);
  EXPECT_TRUE(bus.results.empty()) << "answered before the save ended";
  {
    const std::lock_guard lock(m);
    released = true;
  }
  cv.notify_all();
  turn_until(service, &map, bus, 3);

  ASSERT_EQ(bus.results.size(), 3U);
  EXPECT_EQ(bus.results[0].request_id, 7);
  EXPECT_FALSE(bus.results[0].coalesced);
  for (const auto& r : bus.results) {
    EXPECT_EQ(r.status, CommandStatus::kOk) << r.message;
    EXPECT_EQ(r.path, bus.results[0].path);  // one file for all three
    EXPECT_EQ(r.save_number, 1);
    EXPECT_EQ(r.points, 10'000);  // the map as of the snapshot, before the later requests
  }
  EXPECT_TRUE(bus.results[1].coalesced);
  EXPECT_TRUE(bus.results[2].coalesced);
  std::set<std::string> joined = {bus.results[1].requested_by, bus.results[2].requested_by};
  EXPECT_EQ(joined, (std::set<std::string>{"SIGUSR1", "b"}));
  EXPECT_EQ(files_in(dir).size(), 1U);
  EXPECT_EQ(service.stats().coalesced, 2U);
  EXPECT_EQ(service.stats().requests, 3U);
  EXPECT_EQ(service.stats().saved, 1U);
}

TEST(MapSaveService, FailuresAndRejectionsAreAnswered) {
  drivers::capture::Doorbell wake;
  CommandBus bus;
  auto map = random_map(100, 6);
  {
    // A configured folder that does not exist: FAILED with the reason, nothing created.
    const auto missing = test::temp_dir("mapsave-missing") / "no" / "such";
    MapSaveServiceOptions o;
    o.enabled = true;
    o.saver.directory = missing;
    MapSaveService service(o, wake);
    bus.queued.push_back(save_command(1));
    turn_until(service, &map, bus, 1);
    EXPECT_EQ(bus.results[0].status, CommandStatus::kFailed);
    EXPECT_NE(bus.results[0].message.find("does not exist"), std::string::npos)
        << bus.results[0].message;
    EXPECT_TRUE(bus.results[0].path.empty());
    EXPECT_FALSE(std::filesystem::exists(missing));
  }
  bus.results.clear();
  {
    const auto dir = test::temp_dir("mapsave-reject");
    MapSaveServiceOptions o;
    o.enabled = true;
    o.saver.directory = dir;
    MapSaveService service(o, wake);
    CommandRecord unknown = save_command(2);
    unknown.command = 9;
    CommandRecord argument = save_command(3);
    argument.argument = "/tmp/x.pcd";
    bus.queued = {unknown, argument};
    service.turn(&map, &bus);
    // An empty map: FAILED, no file.
    replay::MapAccumulator empty(0.1, 10);
    bus.queued = {save_command(4)};
    service.turn(&empty, &bus);
    ASSERT_EQ(bus.results.size(), 3U);
    EXPECT_EQ(bus.results[0].status, CommandStatus::kRejected);
    EXPECT_NE(bus.results[0].message.find("unknown command 9"), std::string::npos);
    EXPECT_EQ(bus.results[1].status, CommandStatus::kRejected);
    EXPECT_EQ(bus.results[2].status, CommandStatus::kFailed);
    EXPECT_NE(bus.results[2].message.find("empty"), std::string::npos);
    EXPECT_TRUE(files_in(dir).empty());
  }
  bus.results.clear();
  {
    // Saving disabled: commands rejected, signals logged and counted.
    MapSaveServiceOptions o;
    o.enabled = false;
    MapSaveService service(o, wake);
    service.request_from_signal();
    bus.queued = {save_command(5)};
    service.turn(&map, &bus);
    ASSERT_EQ(bus.results.size(), 1U);
    EXPECT_EQ(bus.results[0].status, CommandStatus::kRejected);
    EXPECT_NE(bus.results[0].message.find("disabled"), std::string::npos);
    EXPECT_EQ(service.stats().rejected, 2U);
  }
}

TEST(MapSaveService, SavesAtStopIntoTheDefaultFolder) {
  const auto out = test::temp_dir("mapsave-stop");
  drivers::capture::Doorbell wake;
  MapSaveServiceOptions o;
  o.enabled = true;
  o.at_stop = true;
  o.saver = map_saver_options({}, out, nullptr, false);
  EXPECT_TRUE(o.saver.create_directory);
  MapSaveService service(o, wake);
  CommandBus bus;
  auto map = random_map(500, 7);
  service.request_from_signal();
  service.finish(&map, &bus);  // the pending signal's save, then the stop's
  ASSERT_EQ(bus.results.size(), 2U);
  EXPECT_EQ(bus.results[0].requested_by, "SIGUSR1");
  EXPECT_EQ(bus.results[1].requested_by, "stop");
  for (const auto& r : bus.results) {
    EXPECT_EQ(r.status, CommandStatus::kOk) << r.message;
    EXPECT_EQ(std::filesystem::path(r.path).parent_path(), std::filesystem::absolute(out / "maps"));
  }
  EXPECT_EQ(files_in(out / "maps").size(), 2U);
}

TEST(MapSaverOptions, DefaultFolders) {
  EXPECT_EQ(map_saver_options("/data/maps", "/out", "/var/lib/livod", false).directory,
            "/data/maps");
  EXPECT_FALSE(map_saver_options("/data/maps", {}, nullptr, false).create_directory);
  EXPECT_EQ(map_saver_options({}, "/out", "/var/lib/livod", false).directory, "/out/maps");
  EXPECT_EQ(map_saver_options({}, {}, "/var/lib/livod:/var/lib/other", false).directory,
            "/var/lib/livod/maps");
  EXPECT_EQ(map_saver_options({}, {}, nullptr, true).directory, "maps");
  EXPECT_TRUE(map_saver_options({}, {}, nullptr, true).overwrite);
}

}  // namespace
}  // namespace livod::daemon::runtime
