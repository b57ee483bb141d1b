// An Ouster without a metadata file, recorded: the live source fetches the metadata from the
// sensor's HTTP API (port 80 of source.udp.sensor_address), and the recorder keeps the JSON the
// sensor served as <lidar>.json, which the recording's config.yaml names: the recording replays
// with it. The sensor is played by a test HTTP server on 127.0.0.1:80 and the real OS-1-128
// capture sent over loopback, inside a private network namespace of this test process (nothing
// leaves it; port 80 is free there).

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <net/if.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <variant>

#include "daemon/config/load_config.hpp"
#include "daemon/record/record_session.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/runtime/live_lidar_source.hpp"
#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::record {
namespace {

using namespace std::chrono_literals;

constexpr const char* kCapture = "ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3.pcap";
constexpr const char* kMetadata = "ouster/pcaps/OS-1-128_v2.3.0_1024x10.json";

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The sensor's HTTP API: answers every request on 127.0.0.1:80 with the metadata.
class SensorHttp {
 public:
  explicit SensorHttp(std::string body) : body_(std::move(body)) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons(80);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
        ::listen(fd_, 4) != 0) {
      throw std::runtime_error(std::string("cannot listen on 127.0.0.1:80: ") +
                               std::strerror(errno));
    }
    thread_ = std::jthread([this](const std::stop_token& stop) {
      while (!stop.stop_requested()) {
        pollfd p{fd_, POLLIN, 0};
        if (::poll(&p, 1, 20) != 1) continue;
        const int c = ::accept(fd_, nullptr, nullptr);
        if (c < 0) continue;
        std::string request;
        char buf[2048];
        while (request.find("\r\n\r\n") == std::string::npos) {
          pollfd r{c, POLLIN, 0};
          if (::poll(&r, 1, 2000) != 1) break;
          const ssize_t n = ::recv(c, buf, sizeof(buf), 0);
          if (n <= 0) break;
          request.append(buf, static_cast<std::size_t>(n));
        }
        if (request.rfind("GET /api/v1/sensor/metadata ", 0) == 0) ++requests_;
        const std::string response =
            "HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: " +
            std::to_string(body_.size()) + "\r\nConnection: close\r\n\r\n" + body_;
        std::size_t sent = 0;
        while (sent < response.size()) {
          const ssize_t n = ::send(c, response.data() + sent, response.size() - sent, MSG_NOSIGNAL);
          if (n <= 0) break;
          sent += static_cast<std::size_t>(n);
        }
        ::close(c);
      }
    });
  }
  ~SensorHttp() {
    thread_.request_stop();
    thread_.join();
    ::close(fd_);
  }
  SensorHttp(const SensorHttp&) = delete;
  SensorHttp& operator=(const SensorHttp&) = delete;
  [[nodiscard]] int requests() const { return requests_.load(); }

 private:
  std::string body_;
  int fd_ = -1;
  std::atomic<int> requests_{0};
  std::jthread thread_;  // last
};

class RecordOuster : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_EQ(::unshare(CLONE_NEWNET), 0) << "unshare(CLONE_NEWNET): " << std::strerror(errno);
    const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
    ASSERT_EQ(::ioctl(s, SIOCGIFFLAGS, &ifr), 0);
    ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP);
    ASSERT_EQ(::ioctl(s, SIOCSIFFLAGS, &ifr), 0);
    ::close(s);
  }
};

TEST_F(RecordOuster, WithoutAMetadataFileTheMetadataFetchedFromTheSensorIsRecorded) {
  const std::string served = read_text(test::data_path(kMetadata));
  ASSERT_FALSE(served.empty());
  SensorHttp http(served);
  const auto dir = test::temp_dir("record-ouster");
  std::filesystem::remove_all(dir / "rec");
  std::ofstream(dir / "live.yaml") << R"(body_frame: os1.imu
sensors:
  - name: os1
    driver: ouster
    model: OS-1-128
    source: {udp: {sensor_address: 127.0.0.1, bind_address: 127.0.0.1}}
    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}
)";
  const ConfigResult loaded = load_config(dir / "live.yaml");
  for (const auto& p : loaded.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(loaded.source, p);
  }
  EXPECT_TRUE(record_problems(loaded.config).empty());
  const SensorConfig& sensor = *loaded.config.find_sensor("os1");

  RecordSession session(loaded.config, dir / "rec");
  runtime::LiveOptions lo;
  lo.ephemeral_ports = true;
  lo.recorder = &session.recorder();
  auto live = runtime::open_live_lidar(sensor, lo);
  session.start();
  std::uint16_t lidar_port = 0;
  for (const auto& [stream, port] : live->local_ports()) {
    if (stream == "lidar") lidar_port = port;
  }
  ASSERT_NE(lidar_port, 0);
  // The source asks the sensor for its metadata as soon as it has no decoder.
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (live->health(host_now())->metadata_refreshes == 0 &&
         std::chrono::steady_clock::now() < deadline) {
    live->supervise(host_now());
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_EQ(live->health(host_now())->metadata_refreshes, 1U);
  EXPECT_EQ(http.requests(), 1);

  // The sensor's point packets (the OS-1-128 capture's lidar port), paced a little.
  const int tx = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  to.sin_port = htons(lidar_port);
  io::PcapReader reader(test::data_path(kCapture));
  std::size_t sent = 0;
  drivers::DecoderSinks sinks;
  std::size_t live_scans = 0;
  sinks.on_scan = [&](const LidarScan&) { ++live_scans; };
  sinks.on_imu = [](const ImuSample&) {};
  while (const auto d = reader.next()) {
    if (d->dst_port != 7502) continue;
    ASSERT_EQ(::sendto(tx, d->payload.data(), d->payload.size(), 0,
                       reinterpret_cast<const sockaddr*>(&to), sizeof(to)),
              static_cast<ssize_t>(d->payload.size()));
    if (++sent % 16 == 0) {
      std::this_thread::sleep_for(1ms);
      while (live->peek_time()) live->deliver(sinks);
    }
  }
  ::close(tx);
  std::this_thread::sleep_for(200ms);
  live->stop();
  while (live->peek_time()) live->deliver(sinks);
  live->finish(sinks);
  EXPECT_TRUE(session.finish().empty());

  // The recording: the sensor's JSON byte for byte, named by config.yaml, noted in recording.txt.
  EXPECT_EQ(read_text(dir / "rec" / "os1.json"), served);
  EXPECT_NE(read_text(dir / "rec" / "recording.txt").find("os1.json: the metadata fetched"),
            std::string::npos)
      << read_text(dir / "rec" / "recording.txt");
  const auto stats = session.recorder().stats().at(0);
  EXPECT_EQ(stats.packets, sent);
  const ConfigResult recorded = load_config(dir / "rec" / "config.yaml");
  for (const auto& p : recorded.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(recorded.source, p);
  }
  const SensorConfig* os1 = recorded.config.find_sensor("os1");
  ASSERT_NE(os1, nullptr);
  EXPECT_EQ(os1->metadata, dir / "rec" / "os1.json");
  const auto* replay = std::get_if<ReplaySourceConfig>(&os1->source);
  ASSERT_NE(replay, nullptr);
  auto source = replay::make_source(*os1, *replay, {});
  std::size_t replayed_scans = 0;
  sinks.on_scan = [&](const LidarScan&) { ++replayed_scans; };
  while (source->peek_time()) source->deliver(sinks);
  source->finish(sinks);
  std::printf("[record-ouster] %zu packets sent, %llu recorded; scans live %zu, replayed %zu\n",
              sent, static_cast<unsigned long long>(stats.packets), live_scans, replayed_scans);
  EXPECT_GE(replayed_scans, 2U);
  EXPECT_EQ(replayed_scans, live_scans);
}

// A sensor that never answers: the recording says so (the pcap replays only with the metadata).
TEST_F(RecordOuster, MetadataThatNeverCameIsReported) {
  const auto dir = test::temp_dir("record-ouster-silent");
  RecorderOptions options;
  options.dir = dir / "rec";
  std::filesystem::remove_all(options.dir);
  Recorder recorder(options);
  recorder.add_packet_stream({"os1", "lidar", 65536, 0});
  recorder.expect_metadata("os1");
  recorder.start();
  const auto problems = recorder.stop();
  ASSERT_EQ(problems.size(), 1U);
  EXPECT_NE(problems[0].find("os1.json: the sensor's metadata was never fetched"),
            std::string::npos)
      << problems[0];
  EXPECT_FALSE(std::filesystem::exists(dir / "rec" / "os1.json"));
  // A re-initialised sensor's new metadata is kept beside the first.
  Recorder again({.dir = dir / "rec2"});
  again.add_packet_stream({"os1", "lidar", 65536, 0});
  again.expect_metadata("os1");
  again.start();
  again.save_metadata("os1", "{\"a\": 1}");
  again.save_metadata("os1", "{\"a\": 1}");  // unchanged: not written again
  again.save_metadata("os1", "{\"a\": 2}");
  EXPECT_TRUE(again.stop().empty());
  EXPECT_EQ(read_text(dir / "rec2" / "os1.json"), "{\"a\": 1}");
  EXPECT_EQ(read_text(dir / "rec2" / "os1.reinit-1.json"), "{\"a\": 2}");
  EXPECT_FALSE(std::filesystem::exists(dir / "rec2" / "os1.reinit-2.json"));
  EXPECT_EQ(again.stats().at(0).notes.size(), 2U);
}

}  // namespace
}  // namespace livod::daemon::record
