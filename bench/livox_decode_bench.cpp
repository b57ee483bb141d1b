// Livox decode throughput on one core, against the sensors' line rates.
//
//   ./livox_decode_bench --benchmark_min_time=2
//
// Packets are synthesised with the project's own encoders (96 points each, 2 % no-returns,
// ranges 0.5..200 m), so no data files are needed:
//   SDK1 (Avia, Horizon, Tele-15; data type 2, extended cartesian 14 B/point), and
//   SDK2 (Mid-360, HAP; data type 1, cartesian 32-bit 14 B/point).
// Reported: points/s (items_per_second) and `x_line_rate` = points/s / the model's line rate
// (Avia 240 000 points/s single return, Mid-360 200 000 points/s).

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "drivers/lidar_decoder.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "drivers/livox/packets.hpp"

namespace {

namespace lx = livod::livox;

constexpr std::size_t kPackets = 2500;  // 1 s of Avia data: distinct packets, beyond L1/L2
constexpr std::size_t kPointsPerPacket = 96;
constexpr double kAviaLineRate = 240'000.0;
constexpr double kMid360LineRate = 200'000.0;
constexpr std::uint32_t kAviaPointIntervalNs = 4167;

std::array<lx::LivoxPoint, kPointsPerPacket> random_points(std::mt19937& rng) {
  std::uniform_real_distribution<float> range(0.5F, 200.0F);
  std::uniform_real_distribution<float> angle(-0.6F, 0.6F);
  std::array<lx::LivoxPoint, kPointsPerPacket> points{};
  for (auto& p : points) {
    const float r = range(rng);
    const float az = angle(rng);
    const float el = angle(rng) * 0.5F;
    p.x = r * std::cos(el) * std::cos(az);
    p.y = r * std::cos(el) * std::sin(az);
    p.z = r * std::sin(el);
    p.reflectivity = static_cast<std::uint8_t>(rng() & 0xFF);
    p.valid = rng() % 50 != 0;
  }
  return points;
}

std::vector<std::vector<std::byte>> sdk1_packets() {
  std::mt19937 rng(1);
  std::vector<std::vector<std::byte>> packets;
  lx::Sdk1Header h;
  h.data_type = 2;
  h.timestamp = 1'000'000'000;
  for (std::size_t i = 0; i < kPackets; ++i) {
    packets.push_back(lx::encode_sdk1_points(h, random_points(rng)));
    h.timestamp += kPointsPerPacket * kAviaPointIntervalNs;
  }
  return packets;
}

std::vector<std::vector<std::byte>> sdk2_packets() {
  std::mt19937 rng(2);
  std::vector<std::vector<std::byte>> packets;
  lx::Sdk2Header h;
  h.data_type = 1;
  h.timestamp_ns = 1'000'000'000;
  h.time_interval_100ns = 4750;  // 96 points at 200 kpts/s
  for (std::size_t i = 0; i < kPackets; ++i) {
    packets.push_back(lx::encode_sdk2_points(h, random_points(rng)));
    h.timestamp_ns += 480'000;
    ++h.udp_cnt;
  }
  return packets;
}

void report(benchmark::State& state, std::uint64_t points, double line_rate) {
  state.SetItemsProcessed(static_cast<std::int64_t>(points));
  state.counters["x_line_rate"] =
      benchmark::Counter(static_cast<double>(points) / line_rate, benchmark::Counter::kIsRate);
}

// The pure packet decoders: bytes -> points (units converted, validity flagged).
void BM_DecodeSdk1Avia(benchmark::State& state) {
  const auto packets = sdk1_packets();
  lx::LivoxPacket out;
  std::uint64_t points = 0;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto e = lx::decode_sdk1(packets[i], kAviaPointIntervalNs, 6, out);
    benchmark::DoNotOptimize(e);
    benchmark::DoNotOptimize(out.points[0].x);
    points += out.count;
    i = (i + 1) % packets.size();
  }
  report(state, points, kAviaLineRate);
}
BENCHMARK(BM_DecodeSdk1Avia);

void BM_DecodeSdk2Mid360(benchmark::State& state) {
  const auto packets = sdk2_packets();
  lx::LivoxPacket out;
  std::uint64_t points = 0;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto e = lx::decode_sdk2(packets[i], 4, out);
    benchmark::DoNotOptimize(e);
    benchmark::DoNotOptimize(out.points[0].x);
    points += out.count;
    i = (i + 1) % packets.size();
  }
  report(state, points, kMid360LineRate);
}
BENCHMARK(BM_DecodeSdk2Mid360);

// The whole LidarDecoder: decode + 10 Hz scan assembly + gap detection, as the consumer runs it.
// Points counted are the ones emitted in scans (no-returns dropped). The sensor timestamp (and
// the SDK2 udp_cnt) of each packet is rewritten before it is decoded, so that time keeps moving
// forward across laps of the packet ring as in a real stream (an 8-byte store per packet).
struct WireLayout {
  std::size_t timestamp_offset;
  std::int64_t packet_span_ns;
  bool has_udp_cnt;
};
constexpr WireLayout kSdk1Layout{10, kPointsPerPacket* kAviaPointIntervalNs, false};
constexpr WireLayout kSdk2Layout{28, 480'000, true};

void run_decoder(benchmark::State& state, const char* model,
                 std::vector<std::vector<std::byte>> packets, const WireLayout& layout,
                 double line_rate) {
  lx::LivoxDecoder decoder(*lx::livox_model(model), lx::LivoxDecoderOptions{});
  std::uint64_t points = 0;
  livod::drivers::DecoderSinks sinks;
  sinks.on_scan = [&points](const livod::LidarScan& scan) { points += scan.size(); };
  std::size_t i = 0;
  std::uint64_t sensor_ns = 1'000'000'000;
  std::uint16_t udp_cnt = 0;
  for (auto _ : state) {
    std::vector<std::byte>& p = packets[i];
    std::memcpy(p.data() + layout.timestamp_offset, &sensor_ns, sizeof(sensor_ns));
    if (layout.has_udp_cnt) std::memcpy(p.data() + 7, &udp_cnt, sizeof(udp_cnt));
    decoder.on_packet(livod::drivers::PacketView{p, static_cast<std::int64_t>(sensor_ns), 56001},
                      sinks);
    sensor_ns += static_cast<std::uint64_t>(layout.packet_span_ns);
    ++udp_cnt;
    i = (i + 1) % packets.size();
  }
  decoder.flush(sinks);
  if (decoder.counters().sequence_gaps != 0 || decoder.counters().decode_errors != 0) {
    state.SkipWithError("the synthetic stream has gaps or errors");
  }
  report(state, points, line_rate);
}

void BM_LivoxDecoderAvia(benchmark::State& state) {
  run_decoder(state, "AVIA", sdk1_packets(), kSdk1Layout, kAviaLineRate);
}
BENCHMARK(BM_LivoxDecoderAvia);

void BM_LivoxDecoderMid360(benchmark::State& state) {
  run_decoder(state, "MID-360", sdk2_packets(), kSdk2Layout, kMid360LineRate);
}
BENCHMARK(BM_LivoxDecoderMid360);

}  // namespace

BENCHMARK_MAIN();
