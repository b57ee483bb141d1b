// The live LiDAR source of a family without an IMU or supervision (Hesai): the real PandarXT-32
// capture sent over loopback at its recorded pace into open_live_lidar (capture threads -> rings
// sized by the family table -> the family's decoder) gives the scans the capture gives when
// decoded directly, with nothing lost or refused.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>

#include "daemon/config/sensor_models.hpp"
#include "daemon/replay/decoder_factory.hpp"
#include "daemon/runtime/live_lidar_source.hpp"
#include "io/pcap.hpp"
#include "tests/runtime/udp_replayer.hpp"
#include "tests/support/data_dir.hpp"

namespace livod {
namespace {

struct ScanDigest {
  std::int64_t start_sensor_ns = 0;
  std::size_t points = 0;
  double sum_x = 0.0;
  bool operator==(const ScanDigest&) const = default;
};

ScanDigest digest(const LidarScan& scan) {
  ScanDigest d{scan.start.sensor.ns, scan.size(), 0.0};
  for (const float x : scan.x) d.sum_x += x;
  return d;
}

daemon::SensorConfig hesai_sensor() {
  daemon::SensorConfig s;
  s.name = "xt32";
  s.driver = daemon::Driver::hesai;
  s.model = "PANDARXT32";
  s.calibration = test::data_path("hesai/PandarXT32.csv");
  s.frame_cut.mode = daemon::default_frame_cut(s.driver);
  daemon::UdpSourceConfig udp;
  udp.bind_address = "127.0.0.1";
  udp.ports = daemon::default_ports(s.driver, s.model);
  udp.socket_buffer_bytes = 16 * 1024 * 1024;
  s.source = udp;
  return s;
}

TEST(LiveLidarSource, HesaiXt32OverLoopbackGivesTheCapturesScans) {
  const auto pcap = test::data_path("hesai/hesai_xt32.pcap");
  const daemon::SensorConfig sensor = hesai_sensor();

  // The capture decoded directly (what `livod decode` and replay do).
  std::vector<ScanDigest> expected;
  {
    const auto decoder = daemon::replay::make_lidar_decoder(sensor);
    io::PcapReader reader(pcap);
    reader.set_port_filter(decoder->default_ports());
    drivers::DecoderSinks sinks;
    sinks.on_scan = [&](const LidarScan& scan) { expected.push_back(digest(scan)); };
    while (const auto d = reader.next()) {
      decoder->on_packet(drivers::PacketView{d->payload, d->capture_time_ns, d->dst_port}, sinks);
    }
    decoder->flush(sinks);
  }
  ASSERT_GE(expected.size(), 3U);

  daemon::runtime::LiveOptions options;
  options.ephemeral_ports = true;
  const auto source = daemon::runtime::open_live_lidar(sensor, options);
  const auto& udp = std::get<daemon::UdpSourceConfig>(sensor.source);
  std::vector<test::UdpRoute> routes;
  for (const auto& [stream, port] : source->local_ports()) {
    if (stream == "lidar") routes.push_back({udp.ports.lidar, port});
    if (stream == "position") routes.push_back({udp.ports.position, port});
  }
  ASSERT_EQ(routes.size(), 2U) << "a point stream and a GPS stream";

  test::SenderResult sent;
  std::atomic<bool> done{false};
  std::thread sender([&] {
    sent = test::send_capture(pcap, routes);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    done = true;
  });
  std::vector<ScanDigest> live;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& scan) { live.push_back(digest(scan)); };
  while (!done) {
    if (source->peek_time()) {
      source->deliver(sinks);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  sender.join();
  source->stop();
  while (!source->exhausted()) source->deliver(sinks);
  source->finish(sinks);

  EXPECT_GT(sent.sent, 0U);
  EXPECT_EQ(live, expected);
  const auto health = source->health(host_now());
  ASSERT_TRUE(health.has_value());
  EXPECT_EQ(health->decoder.decode_errors, 0U);
  EXPECT_EQ(health->decoder.sequence_gaps, 0U);
  EXPECT_EQ(health->lost_packets(), 0U);
  for (const auto& s : health->streams) EXPECT_EQ(s.capture.truncated, 0U) << s.name;
  std::printf("[live] hesai: %llu datagrams sent, %zu scans (decode: %zu)\n",
              static_cast<unsigned long long>(sent.sent), live.size(), expected.size());
}

}  // namespace
}  // namespace livod
