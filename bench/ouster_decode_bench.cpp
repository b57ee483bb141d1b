// Ouster decode throughput on one core: real packets through OusterDecoder (validation, XYZ,
// scan assembly), reported as pixels per second and as a multiple of the sensor's line rate.
//
// Line rate of the largest configuration: OS1-128 at 1024x20 (or 2048x10) = 128 x 1024 x 20
// = 2.62 M pixels/s. The RNG19 capture is an OS-2-128 FW 2.3 frame, byte-for-byte the same
// packet layout as an OS1-128 in RNG19_RFL8_SIG16_NIR16.
//
// Data: $LIVOD_DATA_DIR or ../shared/data next to the repository.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "drivers/ouster/crc64.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "io/pcap.hpp"

namespace {

using livod::drivers::ouster::OusterDecoder;
using livod::drivers::ouster::SensorMetadata;

constexpr double kLineRatePixelsPerSecond = 128.0 * 1024.0 * 20.0;

std::filesystem::path data_dir() {
  if (const char* env = std::getenv("LIVOD_DATA_DIR"); env != nullptr && *env != '\0') return env;
  return std::filesystem::path(__FILE__).parent_path() / "../../shared/data";
}

struct Recording {
  SensorMetadata metadata;
  std::vector<std::vector<std::byte>> lidar_packets;  // one frame
};

Recording load(const std::string& pcap, const std::string& json) {
  Recording r;
  r.metadata = livod::drivers::ouster::load_metadata(data_dir() / "ouster/pcaps" / json);
  const auto format = livod::drivers::ouster::PacketFormat::from_metadata(r.metadata);
  livod::io::PcapReader reader(data_dir() / "ouster/pcaps" / pcap);
  while (auto d = reader.next()) {
    if (d->payload.size() == format.lidar_packet_size &&
        r.lidar_packets.size() < format.columns_per_frame / format.columns_per_packet) {
      r.lidar_packets.emplace_back(d->payload.begin(), d->payload.end());
    }
  }
  return r;
}

// Decodes the same frame again and again; the frame id is advanced each time (2 bytes in each
// packet header, FW 2.3 has no CRC to update) so that every pass is a new frame, not late packets.
void decode_frames(benchmark::State& state, const std::string& pcap, const std::string& json) {
  Recording rec;
  try {
    rec = load(pcap, json);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  OusterDecoder decoder(rec.metadata);
  const auto& format = decoder.packet_format();
  if (rec.lidar_packets.size() * format.columns_per_packet != format.columns_per_frame) {
    state.SkipWithError("capture does not hold one whole frame");
    return;
  }
  std::size_t points = 0;
  livod::drivers::DecoderSinks sinks;
  sinks.on_scan = [&points](const livod::LidarScan& s) { points += s.size(); };
  std::uint16_t frame_id = 0;
  for (auto _ : state) {
    ++frame_id;
    for (auto& packet : rec.lidar_packets) {
      std::memcpy(packet.data() + 2, &frame_id, sizeof(frame_id));
      decoder.on_packet({packet, 0, 7502}, sinks);
    }
  }
  const double pixels_per_frame =
      static_cast<double>(format.pixels_per_column) * format.columns_per_frame;
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pixels_per_frame));
  state.counters["pixels/s"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * pixels_per_frame, benchmark::Counter::kIsRate);
  state.counters["points/s"] =
      benchmark::Counter(static_cast<double>(points), benchmark::Counter::kIsRate);
  state.counters["x_line_rate"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * pixels_per_frame / kLineRatePixelsPerSecond,
      benchmark::Counter::kIsRate);
  if (decoder.counters().decode_errors != 0 || decoder.counters().incomplete_scans != 0) {
    state.SkipWithError("decode errors or incomplete scans while benchmarking");
  }
}

void BM_OusterDecodeRng19Os128(benchmark::State& state) {
  decode_frames(state, "OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json");
}
BENCHMARK(BM_OusterDecodeRng19Os128)->Unit(benchmark::kMillisecond);

void BM_OusterDecodeRng15Os128(benchmark::State& state) {
  decode_frames(state, "OS-1-128_v2.3.0_1024x10_lb_n3.pcap", "OS-1-128_v2.3.0_1024x10.json");
}
BENCHMARK(BM_OusterDecodeRng15Os128)->Unit(benchmark::kMillisecond);

void BM_OusterDecodeDualOs32(benchmark::State& state) {
  decode_frames(state, "OS-0-32-U1_v2.2.0_1024x10.pcap", "OS-0-32-U1_v2.2.0_1024x10.json");
}
BENCHMARK(BM_OusterDecodeDualOs32)->Unit(benchmark::kMillisecond);

// CRC-64 over one RNG19 128-beam packet (FW >= 2.5 checks this on every packet).
void BM_OusterCrc64Packet(benchmark::State& state) {
  std::vector<std::byte> packet(24832);
  for (std::size_t i = 0; i < packet.size(); ++i) packet[i] = static_cast<std::byte>(i * 7);
  for (auto _ : state) {
    benchmark::DoNotOptimize(livod::drivers::ouster::crc64_xz(packet));
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * packet.size()));
}
BENCHMARK(BM_OusterCrc64Packet);

}  // namespace

BENCHMARK_MAIN();
