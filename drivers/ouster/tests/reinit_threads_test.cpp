// Ouster re-initialisation on the live path: the real OS-1-128 capture is sent over loopback with
// the sensor's init_id changed from its second frame on (as after a sensor restart). The decoder
// notices, OusterReinitHandler asks OusterMetadataFetcher for the metadata (served over HTTP by a
// test thread on 127.0.0.1), and the consumer continues with a decoder built from it; the sockets,
// rings and capture threads are never restarted. No external address is contacted.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "drivers/capture/live_source.hpp"
#include "drivers/capture/pcap_pacer.hpp"
#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "drivers/ouster/reinit.hpp"
#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers {
namespace {

using std::chrono::milliseconds;
using std::chrono::steady_clock;
using namespace capture;  // NOLINT(google-build-using-namespace): a test of the capture runtime
using ouster::OusterFetchCounters;
using ouster::OusterMetadataFetcher;
using ouster::OusterMetadataFetcherConfig;
using ouster::OusterReinitHandler;

constexpr std::uint32_t kLoopback = 0x7F000001;
constexpr const char* kCapture = "ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3.pcap";
constexpr const char* kMetadata = "ouster/pcaps/OS-1-128_v2.3.0_1024x10.json";
constexpr std::uint32_t kOldInitId = 7109750;  // the metadata's initialization_id
constexpr std::uint32_t kNewInitId = 7109751;

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Serves `body` as the answer to every GET on 127.0.0.1 until destroyed; with `stall`, accepts
// and never answers (the client's timeout must end the exchange).
class MetadataServer {
 public:
  explicit MetadataServer(std::string body, bool stall = false)
      : body_(std::move(body)), stall_(stall) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (listen_fd_ < 0 ||
        ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
        ::listen(listen_fd_, 8) != 0) {
      throw std::runtime_error("test server setup failed");
    }
    socklen_t len = sizeof(addr);
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    thread_ = std::jthread([this](const std::stop_token& stop) { serve(stop); });
  }
  ~MetadataServer() {
    thread_.request_stop();
    thread_.join();
    ::close(listen_fd_);
  }
  MetadataServer(const MetadataServer&) = delete;
  MetadataServer& operator=(const MetadataServer&) = delete;

  [[nodiscard]] std::uint16_t port() const { return port_; }
  [[nodiscard]] int requests() const { return requests_.load(); }
  [[nodiscard]] bool saw_metadata_path() const { return saw_metadata_path_.load(); }

 private:
  void serve(const std::stop_token& stop) {
    while (!stop.stop_requested()) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) != 1) continue;
      const int fd = ::accept(listen_fd_, nullptr, nullptr);
      if (fd < 0) continue;
      std::string request;
      char buf[4096];
      while (request.find("\r\n\r\n") == std::string::npos) {
        pollfd r{fd, POLLIN, 0};
        if (::poll(&r, 1, 2000) != 1) break;
        const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
        if (n <= 0) break;
        request.append(buf, static_cast<std::size_t>(n));
      }
      ++requests_;
      if (request.rfind("GET /api/v1/sensor/metadata ", 0) == 0) saw_metadata_path_ = true;
      if (stall_) {
        // Hold the connection until the client gives up (closes) or the test ends.
        while (!stop.stop_requested()) {
          pollfd r{fd, POLLIN, 0};
          if (::poll(&r, 1, 20) == 1 && ::recv(fd, buf, sizeof(buf), 0) <= 0) break;
        }
      } else {
        const std::string response =
            "HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: " +
            std::to_string(body_.size()) + "\r\nConnection: close\r\n\r\n" + body_;
        std::size_t sent = 0;
        while (sent < response.size()) {
          const ssize_t n =
              ::send(fd, response.data() + sent, response.size() - sent, MSG_NOSIGNAL);
          if (n <= 0) break;
          sent += static_cast<std::size_t>(n);
        }
      }
      ::close(fd);
    }
  }

  std::string body_;
  bool stall_;
  int listen_fd_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<int> requests_{0};
  std::atomic<bool> saw_metadata_path_{false};
  std::jthread thread_;  // last
};

// The metadata the restarted sensor serves: same calibration, new initialization_id.
std::string restarted_metadata_json() {
  std::string json = read_text(test::data_path(kMetadata));
  const std::string old_text = "\"initialization_id\": " + std::to_string(kOldInitId);
  const auto at = json.find(old_text);
  if (at == std::string::npos) throw std::runtime_error("initialization_id not found");
  json.replace(at, old_text.size(), "\"initialization_id\": " + std::to_string(kNewInitId));
  return json;
}

struct Split {
  std::filesystem::path first;   // frames 1-2 (frame 2 already with the new init_id)
  std::filesystem::path second;  // frame 3
};

// Writes the capture as two pcaps, with init_id (bytes 4-6 of a non-LEGACY lidar packet header)
// set to kNewInitId from the second frame on.
Split restarted_captures() {
  const auto dir = test::temp_dir("ouster_reinit");
  Split split{dir / "frames_1_2.pcap", dir / "frame_3.pcap"};
  io::PcapWriter first(split.first, io::PcapWriter::Options{.mtu = 9000});
  io::PcapWriter second(split.second, io::PcapWriter::Options{.mtu = 9000});
  io::PcapReader reader(test::data_path(kCapture));
  std::optional<std::uint16_t> first_frame;
  bool in_second_part = false;
  while (auto d = reader.next()) {
    std::vector<std::byte> payload(d->payload.begin(), d->payload.end());
    if (d->dst_port == 7502 && payload.size() > 32) {
      const auto frame_id = static_cast<std::uint16_t>(
          std::to_integer<unsigned>(payload[2]) | (std::to_integer<unsigned>(payload[3]) << 8));
      if (!first_frame) first_frame = frame_id;
      const int frame_index = static_cast<std::uint16_t>(frame_id - *first_frame);
      if (frame_index >= 1) {
        for (int i = 0; i < 3; ++i) {
          payload[4 + static_cast<std::size_t>(i)] =
              static_cast<std::byte>((kNewInitId >> (8 * i)) & 0xFF);
        }
      }
      if (frame_index >= 2) in_second_part = true;
    }
    (in_second_part ? second : first)
        .write_udp(d->capture_time_ns, d->src_ip, d->src_port, d->dst_ip, d->dst_port, payload);
  }
  first.flush();
  second.flush();
  return split;
}

std::vector<LidarScan> decode_reference() {
  ouster::OusterDecoder decoder(ouster::load_metadata(test::data_path(kMetadata)));
  std::vector<LidarScan> scans;
  DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) { scans.push_back(s); };
  io::PcapReader reader(test::data_path(kCapture));
  while (auto d = reader.next()) {
    decoder.on_packet(PacketView{d->payload, d->capture_time_ns, d->dst_port}, sinks);
  }
  decoder.flush(sinks);
  return scans;
}

class OusterReinit : public ::testing::Test {
 protected:
  OusterReinit()
      : source_(config(), std::make_unique<ouster::OusterDecoder>(
                              ouster::load_metadata(test::data_path(kMetadata)))) {
    sinks_.on_scan = [this](const LidarScan& s) { scans_.push_back(s); };
  }

  static LiveSourceConfig config() {
    LiveSourceConfig c;
    c.name = "os1";
    for (const auto& [name, port] : {std::pair{"lidar", 7502}, std::pair{"imu", 7503}}) {
      UdpStreamConfig s;
      s.name = name;
      s.socket.bind_address = "127.0.0.1";
      s.socket.max_datagram_bytes = 9000;
      s.socket.receive_buffer_bytes = 16 << 20;
      s.ring_capacity = 1024;
      s.thread.reported_port = static_cast<std::uint16_t>(port);
      c.streams.push_back(s);
    }
    return c;
  }

  // Sends a capture at its recorded pace and decodes until every datagram went through.
  void send_and_consume(const std::filesystem::path& capture) {
    const std::vector<UdpRoute> routes{{7502, kLoopback, source_.stream(0).local_port()},
                                       {7503, kLoopback, source_.stream(1).local_port()}};
    const PaceResult paced = send_pcap_paced(capture, routes, PaceOptions{1.0});
    ASSERT_EQ(paced.failed, 0u);
    expected_ += paced.delivered;
    const auto deadline = steady_clock::now() + std::chrono::seconds(20);
    while (source_.consumer().counters().packets < expected_ && steady_clock::now() < deadline) {
      if (source_.consumer().poll(sinks_) == 0) std::this_thread::sleep_for(milliseconds(1));
    }
    ASSERT_EQ(source_.consumer().counters().packets, expected_);
  }

  ouster::OusterDecoder& decoder() {
    return dynamic_cast<ouster::OusterDecoder&>(source_.consumer().decoder());
  }

  LiveSource source_;
  DecoderSinks sinks_;
  std::vector<LidarScan> scans_;
  std::uint64_t expected_ = 0;
};

TEST_F(OusterReinit, NewInitIdRefetchesMetadataAndSwapsTheDecoderWithoutRestarting) {
  const Split split = restarted_captures();
  const std::vector<LidarScan> reference = decode_reference();
  ASSERT_EQ(reference.size(), 3u);
  MetadataServer server(restarted_metadata_json());
  OusterMetadataFetcher fetcher({.host = "127.0.0.1", .port = server.port()});
  OusterReinitHandler handler(fetcher, ouster::OusterDecoderOptions{}, Nanoseconds(100'000'000));

  // Frames 1-2: the old decoder sees the new init_id at frame 2 and says its metadata is stale.
  send_and_consume(split.first);
  EXPECT_EQ(decoder().ouster_counters().init_id_changes, 1u);
  EXPECT_TRUE(decoder().metadata_init_id_mismatch());
  ASSERT_EQ(scans_.size(), 2u);

  // The scheduler's maintenance: ask, then install the decoder built from the fetched metadata.
  const auto deadline = steady_clock::now() + std::chrono::seconds(20);
  while (handler.metadata_refreshes() == 0 && steady_clock::now() < deadline) {
    handler.maintain(source_.consumer(), host_now());
    std::this_thread::sleep_for(milliseconds(2));
  }
  ASSERT_EQ(handler.metadata_refreshes(), 1u);
  EXPECT_EQ(server.requests(), 1);
  EXPECT_TRUE(server.saw_metadata_path());
  EXPECT_EQ(fetcher.counters().successes, 1u);
  EXPECT_EQ(source_.consumer().counters().decoder_replacements, 1u);
  EXPECT_EQ(decoder().metadata().initialization_id, kNewInitId);
  EXPECT_FALSE(decoder().metadata_init_id_mismatch());

  // Frame 3 through the same sockets, rings and threads, decoded by the new decoder.
  send_and_consume(split.second);
  handler.maintain(source_.consumer(), host_now());
  source_.consumer().flush(sinks_);
  EXPECT_EQ(decoder().ouster_counters().init_id_changes, 0u);
  EXPECT_FALSE(decoder().metadata_init_id_mismatch());
  EXPECT_EQ(decoder().counters().scans, 1u);
  EXPECT_EQ(decoder().counters().incomplete_scans, 0u);
  EXPECT_EQ(server.requests(), 1);  // nothing more to fetch

  // Same geometry as decoding the untouched capture.
  ASSERT_EQ(scans_.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_EQ(scans_[i].size(), reference[i].size()) << i;
    EXPECT_EQ(scans_[i].x, reference[i].x) << i;
    EXPECT_EQ(scans_[i].y, reference[i].y) << i;
    EXPECT_EQ(scans_[i].z, reference[i].z) << i;
    EXPECT_EQ(scans_[i].t_offset_ns, reference[i].t_offset_ns) << i;
  }

  SourceHealth health = source_.update_health(host_now());
  handler.note_health(health);
  EXPECT_EQ(health.sensor_reinits, 1u);
  EXPECT_EQ(health.metadata_refreshes, 1u);
  EXPECT_TRUE(health.last_error.empty()) << health.last_error;
  EXPECT_EQ(health.decoder.scans, 3u);  // totals over both decoders
  for (const StreamHealth& s : health.streams) {
    EXPECT_EQ(s.capture.kernel_drops, 0u);
    EXPECT_EQ(s.capture.ring_overruns, 0u);
  }

  // A stream that comes back from STALE (LEGACY sensors carry no init_id) refreshes once more.
  health.streams[0].recoveries = 1;
  handler.note_health(health);
  while (handler.metadata_refreshes() == 1 && steady_clock::now() < deadline) {
    handler.maintain(source_.consumer(), host_now());
    std::this_thread::sleep_for(milliseconds(2));
  }
  EXPECT_EQ(handler.metadata_refreshes(), 2u);
  EXPECT_EQ(server.requests(), 2);
  handler.maintain(source_.consumer(), host_now());
  EXPECT_EQ(server.requests(), 2);  // once per recovery
}

TEST(OusterMetadataFetcher, FailuresAreReportedAndRetriesAreSpaced) {
  // A port nobody listens on: bind one, read its number, close it again.
  std::uint16_t closed_port = 0;
  {
    MetadataServer placeholder("");
    closed_port = placeholder.port();
  }
  OusterMetadataFetcher fetcher(
      {.host = "127.0.0.1", .port = closed_port, .timeout = milliseconds(500)});
  PacketRing ring(4, 16);
  StreamConsumer consumer(
      std::make_unique<ouster::OusterDecoder>(ouster::load_metadata(test::data_path(kMetadata))),
      {&ring});
  OusterReinitHandler handler(fetcher, {}, Nanoseconds(3'600'000'000'000));  // 1 h between tries
  SourceHealth health;
  health.streams.resize(1);
  health.streams[0].recoveries = 1;  // ask once
  handler.note_health(health);
  const auto deadline = steady_clock::now() + std::chrono::seconds(20);
  while (fetcher.counters().failures == 0 && steady_clock::now() < deadline) {
    handler.maintain(consumer, host_now());
    std::this_thread::sleep_for(milliseconds(2));
  }
  for (int i = 0; i < 20; ++i) handler.maintain(consumer, host_now());
  EXPECT_EQ(fetcher.counters().requests, 1u);  // spaced by the retry interval
  EXPECT_EQ(fetcher.counters().failures, 1u);
  EXPECT_EQ(handler.metadata_refreshes(), 0u);
  handler.note_health(health);
  EXPECT_NE(health.last_error.find("127.0.0.1"), std::string::npos) << health.last_error;
}

TEST(OusterMetadataFetcher, StopsWhileAFetchIsInProgress) {
  MetadataServer server("", /*stall=*/true);
  auto fetcher = std::make_unique<OusterMetadataFetcher>(OusterMetadataFetcherConfig{
      .host = "127.0.0.1", .port = server.port(), .timeout = milliseconds(300)});
  fetcher->request();
  const auto deadline = steady_clock::now() + std::chrono::seconds(20);
  while (server.requests() == 0 && steady_clock::now() < deadline) {
    std::this_thread::sleep_for(milliseconds(1));
  }
  EXPECT_TRUE(fetcher->busy());
  fetcher.reset();  // joins once the HTTP timeout ends the exchange
  EXPECT_EQ(server.requests(), 1);
}

}  // namespace
}  // namespace livod::drivers
