// Velodyne decode throughput on one core, against the sensors' line rates.
//
//   ./velodyne_decode_bench --benchmark_min_time=2
//
// Packets are synthesised (the layout of §4.1: every block flag, a steadily turning azimuth,
// ranges of 1..120 m with 10 % no-returns) so that the benchmark needs no data files. Reported:
// points/s (items_per_second) and `x_line_rate` = points/s divided by the model's single-return
// line rate (VLP-16 0.29 M, VLS-128 2.40 M points/s). The goal is >= 20x.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <vector>

#include "drivers/velodyne/data_packet.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"

namespace {

using livod::drivers::velodyne::Model;
namespace v = livod::drivers::velodyne;

constexpr std::size_t kPackets = 2048;  // a ring of distinct packets (0.33 s of VLS-128 data)

std::vector<std::vector<std::byte>> make_packets(Model model) {
  const auto& t = v::traits(model);
  const v::FiringTiming timing(model);
  // 10 Hz: 36000 counts per 100 ms.
  const double counts_per_ns = 36000.0 / 100e6;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> range(250, 30000);
  std::vector<std::vector<std::byte>> packets(kPackets, std::vector<std::byte>(1206));
  std::uint64_t toh_ns = 1'000'000'000;
  for (auto& p : packets) {
    for (int b = 0; b < 12; ++b) {
      std::uint16_t flag = 0xEEFF;
      if (model == Model::kVls128) flag = static_cast<std::uint16_t>(0xEEFF - 0x1100 * (b % 4));
      const auto azimuth = static_cast<std::uint16_t>(
          static_cast<std::uint64_t>(
              (toh_ns + static_cast<std::uint64_t>(timing.block_reference_ns(false, b))) *
              counts_per_ns) %
          36000);
      const std::size_t base = static_cast<std::size_t>(b) * 100;
      p[base] = static_cast<std::byte>(flag & 0xFF);
      p[base + 1] = static_cast<std::byte>(flag >> 8);
      p[base + 2] = static_cast<std::byte>(azimuth & 0xFF);
      p[base + 3] = static_cast<std::byte>(azimuth >> 8);
      for (int c = 0; c < 32; ++c) {
        const std::size_t at = base + 4 + static_cast<std::size_t>(c) * 3;
        const int raw = (rng() % 10 == 0) ? 0 : range(rng);
        p[at] = static_cast<std::byte>(raw & 0xFF);
        p[at + 1] = static_cast<std::byte>(raw >> 8);
        p[at + 2] = static_cast<std::byte>(rng() & 0xFF);
      }
    }
    const auto toh_us = static_cast<std::uint32_t>(toh_ns / 1000);
    for (int i = 0; i < 4; ++i)
      p[1200 + static_cast<std::size_t>(i)] = static_cast<std::byte>(toh_us >> (8 * i));
    p[1204] = std::byte{0x37};
    p[1205] = std::byte{t.factory_byte};
    toh_ns += static_cast<std::uint64_t>(timing.packet_period_ns(false));
  }
  return packets;
}

void report(benchmark::State& state, Model model, std::uint64_t points) {
  state.SetItemsProcessed(static_cast<std::int64_t>(points));
  state.counters["x_line_rate"] =
      benchmark::Counter(static_cast<double>(points) / v::traits(model).points_per_second,
                         benchmark::Counter::kIsRate);
}

// The pure packet decoder: bytes -> points.
void BM_PacketDecode(benchmark::State& state) {
  const auto model = static_cast<Model>(state.range(0));
  const auto packets = make_packets(model);
  const v::DataPacketDecoder decoder(model, v::default_calibration(model), {});
  std::vector<v::DecodedReturn> out(v::DataPacketDecoder::kMaxReturns);
  std::uint64_t points = 0;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto r = decoder.decode(packets[i], 0.0, out);
    benchmark::DoNotOptimize(out.data());
    points += r.count;
    i = (i + 1) % kPackets;
  }
  report(state, model, points);
}

// The whole driver: decode + gap check + time + scan assembly into LidarScan (what the capture
// thread runs per packet).
void BM_Driver(benchmark::State& state) {
  const auto model = static_cast<Model>(state.range(0));
  auto packets = make_packets(model);
  const std::int64_t period_ns = v::FiringTiming(model).packet_period_ns(false);
  v::VelodyneOptions options;
  options.model = model;
  v::VelodyneDecoder decoder(options);
  livod::drivers::DecoderSinks sinks;
  std::uint64_t points = 0;
  sinks.on_scan = [&points](const livod::LidarScan& scan) { points += scan.size(); };
  std::size_t i = 0;
  std::int64_t host_ns = 1'000'000'000;
  for (auto _ : state) {
    // Keep the timestamps running when the ring wraps (the driver drops packets from the past).
    auto toh_us = static_cast<std::uint32_t>((host_ns / 1000) % 3'600'000'000LL);
    for (int k = 0; k < 4; ++k)
      packets[i][1200 + static_cast<std::size_t>(k)] = static_cast<std::byte>(toh_us >> (8 * k));
    decoder.on_packet(livod::drivers::PacketView{packets[i], host_ns, 2368}, sinks);
    host_ns += period_ns;
    i = (i + 1) % kPackets;
  }
  report(state, model, points);
}

BENCHMARK(BM_PacketDecode)
    ->Arg(static_cast<int>(Model::kVlp16))
    ->Arg(static_cast<int>(Model::kVls128))
    ->ArgName("model");
BENCHMARK(BM_Driver)
    ->Arg(static_cast<int>(Model::kVlp16))
    ->Arg(static_cast<int>(Model::kVls128))
    ->ArgName("model");

}  // namespace

BENCHMARK_MAIN();
