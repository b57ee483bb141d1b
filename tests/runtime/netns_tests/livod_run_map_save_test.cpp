// The real `livod run` process saves its map on SIGUSR1 while it runs, inside the private network
// namespace scripts/netns-run.sh provides (the sensor's fixed ports on loopback). The test is the
// robot: it streams a simulated Mid-360 capture over UDP at the recorded pace and sends SIGUSR1
// twice, seconds apart, then runs `livod save-map` (the request over LCM udpm, answered with the
// file's path). Each request gives a new, complete binary PCD in the configured map folder
// (no partial file left), the daemon keeps estimating (the trajectory covers the whole capture and
// the map at stop holds more points than the first save), and SIGTERM stops it with exit code 0.
// PCL reads these files: tests/runtime/pcl_tests/map_save_pcl_test.cpp.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>
#include <thread>

#include "io/pcap.hpp"
#include "tests/replay/sim_replay.hpp"
#include "tests/runtime/udp_replayer.hpp"
#include "tests/support/process.hpp"

namespace livod {
namespace {

using namespace std::chrono_literals;

bool inside_private_namespace() {
  const char* flag = std::getenv("LIVOD_NETNS");
  return flag != nullptr && std::string(flag) == "1";
}

// POINTS of a binary x y z PCD, checking that the file is exactly header + points.
std::size_t pcd_points(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t points = 0;
  std::size_t header = 0;
  bool xyz = false;
  bool binary = false;
  while (std::getline(in, line)) {
    header += line.size() + 1;
    xyz = xyz || line == "FIELDS x y z";
    if (line.rfind("POINTS ", 0) == 0) points = std::stoul(line.substr(7));
    if (line == "DATA binary") {
      binary = true;
      break;
    }
  }
  EXPECT_TRUE(xyz && binary) << path;
  EXPECT_EQ(std::filesystem::file_size(path), header + 12 * points) << path;
  return points;
}

std::vector<std::filesystem::path> maps_in(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  if (!std::filesystem::is_directory(dir)) return out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ".pcd") out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool wait_for(const std::function<bool()>& done, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(20ms);
  }
  return true;
}

TEST(LivodRunMapSave, Sigusr1SavesTheMapWhileRunning) {
  ASSERT_TRUE(inside_private_namespace())
      << "binds the sensor's fixed ports: run through scripts/netns-run.sh (ctest does)";
  const auto folder = test::simulate(sim::make_scenario("room_handheld_mid360"), 10.0, "run-map");
  const auto out = test::temp_dir("run-map-out");
  const auto maps = out / "maps";
  std::filesystem::create_directories(maps);
  std::string text = test::read_text_file(folder / "config.yaml");
  const std::string replay = "      replay: {file: mid360.pcap}\n";
  const auto at = text.find(replay);
  ASSERT_NE(at, std::string::npos) << "unexpected simulator configuration";
  text.replace(at, replay.size(),
               "      udp: {bind_address: 127.0.0.1, sensor_address: 127.0.0.1,\n"
               "            socket_buffer_bytes: 16777216}\n");
  const std::string outputs = "outputs:\n  trajectory: trajectory.txt\n";
  const auto o = text.find(outputs);
  ASSERT_NE(o, std::string::npos) << "unexpected simulator outputs";
  text.replace(o, outputs.size(),
               "outputs:\n  trajectory: " + (out / "trajectory.txt").string() +
                   "\n  map_pcd: " + (out / "map.pcd").string() +
                   "\n  lcm: {url: \"udpm://239.255.76.67:7667?ttl=0\"}\n" +
                   "  map_saves: {directory: " + maps.string() + "}\n");
  const auto config = out / "live.yaml";
  std::ofstream(config) << text;

  const auto log = out / "livod.log";
  test::ChildProcess livod({LIVOD_BINARY, "run", "--config", config.string()}, {.output = log});
  ASSERT_TRUE(
      wait_for([&] { return test::read_text_file(log).find("ready") != std::string::npos; }, 30s))
      << test::read_text_file(log);

  const auto pcap = folder / "mid360.pcap";
  std::set<std::uint16_t> ports;
  {
    io::PcapReader reader(pcap);
    while (const auto d = reader.next()) ports.insert(d->dst_port);
  }
  std::vector<test::UdpRoute> routes;
  for (const auto p : ports) routes.push_back({p, p});
  test::SenderResult sent;
  std::jthread sender([&] { sent = test::send_capture(pcap, routes); });

  // 3.5 s in: the filter runs and the map has points. Then again 3 s later.
  std::this_thread::sleep_for(3500ms);
  livod.signal(SIGUSR1);
  ASSERT_TRUE(wait_for([&] { return maps_in(maps).size() == 1; }, 10s))
      << test::read_text_file(log);
  const std::size_t first_points = pcd_points(maps_in(maps)[0]);
  std::this_thread::sleep_for(3000ms);
  livod.signal(SIGUSR1);
  ASSERT_TRUE(wait_for([&] { return maps_in(maps).size() == 2; }, 10s))
      << test::read_text_file(log);
  // `livod save-map` asks over LCM (udpm on the namespace's loopback) and prints the file.
  const auto save_map_out = out / "save-map.txt";
  const int save_map =
      test::run_process({LIVOD_BINARY, "save-map", "--config", config.string(), "--timeout", "20"},
                        {.output = save_map_out}, 30s);
  EXPECT_EQ(save_map, 0) << test::read_text_file(save_map_out) << test::read_text_file(log);
  EXPECT_EQ(test::read_text_file(save_map_out).find((maps / "map-").string()), 0U)
      << test::read_text_file(save_map_out);
  sender.join();
  std::this_thread::sleep_for(1s);
  EXPECT_TRUE(livod.running()) << "the daemon stopped after the saves";
  livod.signal(SIGTERM);
  const auto status = livod.wait_for(10s);
  ASSERT_TRUE(status.has_value()) << "still running 10 s after SIGTERM";
  EXPECT_EQ(*status, 0) << test::read_text_file(log);

  const auto files = maps_in(maps);
  ASSERT_EQ(files.size(), 3U);  // two SIGUSR1, one livod save-map
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(maps),
                          std::filesystem::directory_iterator()),
            3)
      << "a partial file was left in " << maps;
  const std::size_t second_points = pcd_points(files[1]);
  const std::size_t final_points = pcd_points(out / "map.pcd");
  EXPECT_GT(first_points, 0U);
  EXPECT_GE(second_points, first_points);
  EXPECT_GT(final_points, first_points) << "the map did not grow after the first save";
  for (const auto& f : files) {
    EXPECT_EQ(f.filename().string().rfind("map-", 0), 0U) << f;
  }
  // Poses kept coming: the trajectory covers the capture (10 Hz scans, 10 s, minus the IMU
  // initialisation), well beyond the 3.5 s of the first save.
  std::size_t lines = 0;
  {
    std::ifstream in(out / "trajectory.txt");
    std::string line;
    while (std::getline(in, line)) ++lines;
  }
  EXPECT_GT(lines, 70U) << test::read_text_file(log);
  const std::string text_log = test::read_text_file(log);
  EXPECT_NE(text_log.find("map saved: "), std::string::npos) << text_log;
  EXPECT_EQ(text_log.find("map save failed"), std::string::npos) << text_log;
  std::printf("[run-map] saves of %zu and %zu points, %zu at stop, %zu poses, %llu datagrams\n",
              first_points, second_points, final_points, lines,
              static_cast<unsigned long long>(sent.sent));
}

}  // namespace
}  // namespace livod
