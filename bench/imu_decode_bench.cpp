// IMU decode throughput, one core: the CAN decoders (SBG, Bosch MM7, a custom YAML-described
// decoder) on their frames, and the Xsens MTData2 stream decoder on a byte stream read in 64-byte
// chunks (messages torn across reads). items_per_second = samples/s of CPU time.
//
//   ./imu_decode_bench --benchmark_min_time=1

#include <benchmark/benchmark.h>

#include <vector>

#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/custom_can.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/imu/xsens_mtdata2.hpp"

namespace {

using livod::imu::CanRecord;

constexpr int kSamples = 1000;

template <class Encode>
std::vector<CanRecord> frames_of(Encode&& encode) {
  std::vector<CanRecord> out;
  for (int k = 0; k < kSamples; ++k) {
    const Eigen::Vector3d a(0.01 * k, -0.2, 9.81);
    const Eigen::Vector3d g(0.1, -0.001 * k, 0.02);
    for (const auto& f : encode(k, a, g)) out.push_back(f);
  }
  return out;
}

void run_can(benchmark::State& state, livod::imu::CanImuDecoder& decoder,
             const std::vector<CanRecord>& frames) {
  std::size_t samples = 0;
  const livod::imu::ImuSink sink = [&](const livod::ImuSample& s) {
    benchmark::DoNotOptimize(s.gyro_rad_s.data());
    ++samples;
  };
  for (auto _ : state) {
    for (const auto& f : frames) decoder.on_frame(f, sink);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(samples));
}

void BM_SbgCan(benchmark::State& state) {
  livod::imu::SbgCanDecoder d;
  const auto frames = frames_of([](int k, const Eigen::Vector3d& a, const Eigen::Vector3d& g) {
    return livod::imu::encode_sbg_sample(static_cast<std::uint32_t>(5000 * k), a, g, 30.0);
  });
  run_can(state, d, frames);
}
BENCHMARK(BM_SbgCan);

void BM_BoschMm7(benchmark::State& state) {
  livod::imu::BoschMm7Decoder d;
  const auto frames = frames_of([](int k, const Eigen::Vector3d& a, const Eigen::Vector3d& g) {
    return livod::imu::encode_bosch_mm7_sample(static_cast<std::uint8_t>(k & 15), a, g, 30.0);
  });
  run_can(state, d, frames);
}
BENCHMARK(BM_BoschMm7);

void BM_CustomCan(benchmark::State& state) {
  using livod::imu::ImuAxis;
  using livod::imu::ImuUnit;
  livod::imu::CustomCanSpec spec;
  const std::uint32_t ids[3] = {0x178, 0x17C, 0x174};
  for (int a = 0; a < 3; ++a) {
    spec.signals.push_back({static_cast<ImuAxis>(a),
                            ids[a],
                            {32, 16, false, false},
                            0.000127465,
                            -4.1768,
                            ImuUnit::g});
    spec.signals.push_back({static_cast<ImuAxis>(3 + a),
                            ids[a],
                            {0, 16, false, false},
                            0.005,
                            -163.84,
                            ImuUnit::deg_s});
  }
  spec.sample_id = 0x174;
  livod::imu::CustomCanDecoder d(spec);
  const auto frames = frames_of([&](int, const Eigen::Vector3d& a, const Eigen::Vector3d& g) {
    return livod::imu::encode_custom_sample(spec, a, g);
  });
  run_can(state, d, frames);
}
BENCHMARK(BM_CustomCan);

void BM_XsensMtData2(benchmark::State& state) {
  std::vector<std::byte> stream;
  for (int k = 0; k < kSamples; ++k) {
    livod::imu::XsensSample x;
    x.packet_counter = static_cast<std::uint16_t>(k);
    x.sample_time_fine = static_cast<std::uint32_t>(25 * k);
    x.accel_m_s2 = Eigen::Vector3d(0.01 * k, -0.2, 9.81);
    for (const auto b : livod::imu::encode_mtdata2_sample(x))
      stream.push_back(static_cast<std::byte>(b));
  }
  livod::imu::XsensMtData2Decoder d;
  std::size_t samples = 0;
  const livod::imu::ImuSink sink = [&](const livod::ImuSample& s) {
    benchmark::DoNotOptimize(s.accel_m_s2.data());
    ++samples;
  };
  for (auto _ : state) {
    for (std::size_t i = 0; i < stream.size(); i += 64) {
      d.on_bytes({stream.data() + i, std::min<std::size_t>(64, stream.size() - i)}, 0, sink);
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(samples));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * stream.size()));
}
BENCHMARK(BM_XsensMtData2);

}  // namespace

BENCHMARK_MAIN();
