// The simulator's external IMU outputs decode back to the simulated measurements through livod's
// own decoders: a Bosch MM7 candump log and an Xsens MTi serial capture with torn reads,
// corrupted messages and line noise.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>

#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/candump_frames.hpp"
#include "drivers/imu/xsens_mtdata2.hpp"
#include "io/candump.hpp"
#include "io/serial_capture.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/bag_output.hpp"
#include "tools/sim/runner.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

constexpr double kEpoch = 1'700'000'000.0;
constexpr std::int64_t kEpochNs = 1'700'000'000'000'000'000;

SimRunOptions options_for(const std::string& dir, std::uint64_t seed, double duration) {
  SimRunOptions o;
  o.out_dir = test::temp_dir(dir);
  o.seed = seed;
  o.duration_s = duration;
  o.host_epoch_s = kEpoch;
  o.write_images = false;
  return o;
}

TEST(SimImuFormats, BoschMm7CandumpDecodesToTheImuModelWithinTheWireResolution) {
  Scenario scenario = make_scenario("street_vehicle_vlp16");
  scenario.lidars.clear();
  ASSERT_TRUE(scenario.can_imu);
  scenario.can_imu->format = CanImuFormat::kBoschMm7;
  scenario.can_imu->noise.rate_hz = 100.0;
  const SimRunOptions o = options_for("sim_bosch_mm7", 4, 3.0);
  const auto report = run_scenario(scenario, o);

  const CanImuMount& mount = *scenario.can_imu;
  const World world = make_street_world(o.seed, scenario.street_length_m);
  const Trajectory trajectory(scenario.trajectory);
  SceneContext scene{&world, &trajectory};
  ImuModel model(mount.noise, sensor_seed(o.seed, mount.name + "/noise"));
  const std::size_t n = 300;

  io::CandumpReader reader(o.out_dir / (mount.name + ".log"));
  imu::BoschMm7Decoder decoder;
  io::CanFrame frame;
  std::size_t k = 0;
  double max_accel = 0.0;
  double max_gyro = 0.0;
  while (reader.next(frame)) {
    std::optional<ImuSample> sample;
    decoder.on_frame(imu::to_can_record(frame), [&](const ImuSample& s) { sample = s; });
    if (!sample) continue;
    ASSERT_LT(k, n);
    const double t = static_cast<double>(k) / 100.0;
    const ImuTruth m = model.measure(scene.imu_truth(t, mount.T_body_imu));
    max_accel = std::max(max_accel, (sample->accel_m_s2 - m.accel_m_s2).cwiseAbs().maxCoeff());
    max_gyro = std::max(max_gyro, (sample->gyro_rad_s - m.gyro_rad_s).cwiseAbs().maxCoeff());
    // No sensor clock: stamped with TX1's receive time, one frame (232 us) plus the link delay
    // (>= 80 us floor) after the sample, in whole microseconds (candump resolution).
    const std::int64_t after = sample->stamp.host.ns - (kEpochNs + std::llround(t * 1e9));
    EXPECT_GE(after, 232'000 + 80'000 - 1000) << k;
    EXPECT_EQ(sample->stamp.sensor.ns, sample->stamp.host.ns);
    ++k;
  }
  EXPECT_EQ(k, n);
  EXPECT_EQ(report.sensors.at(0).messages, 3 * n);
  EXPECT_EQ(decoder.counters().incomplete, 0u);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0u);
  EXPECT_EQ(decoder.counters().invalid, 0u);
  // Half an LSB: 0.000127465 g and 0.005 deg/s.
  EXPECT_LE(max_accel, 0.5 * 0.000127465 * 9.80665 + 1e-9);
  EXPECT_LE(max_gyro, 0.5 * 0.005 * std::numbers::pi / 180.0 + 1e-12);
  EXPECT_GT(max_accel, 1e-4);  // really quantised
}

TEST(SimImuFormats, XsensSerialCaptureWithTornCorruptedAndNoisyReadsDecodesToTheImuModel) {
  Scenario scenario = make_scenario("street_vehicle_vlp16");
  scenario.lidars.clear();
  SerialImuMount mount;
  mount.name = "xsens";
  mount.clock = ClockFaults{.offset_s = 3.25, .skew_ppm = -30.0, .jitter_s = 0.0, .reset_at_s = -1};
  mount.corrupt_probability = 0.02;
  mount.noise_probability = 0.02;
  mount.max_read_bytes = 50;
  scenario.serial_imu = mount;
  const SimRunOptions o = options_for("sim_xsens", 6, 2.5);
  const auto report = run_scenario(scenario, o);
  const auto& rep = report.sensors.back();
  ASSERT_EQ(rep.kind, "serial_imu");
  const std::size_t n = 1000;  // 2.5 s at 400 Hz
  EXPECT_GT(rep.dropped, 5u);  // corrupted messages

  const World world = make_street_world(o.seed, scenario.street_length_m);
  const Trajectory trajectory(scenario.trajectory);
  SceneContext scene{&world, &trajectory};
  ImuModel model(mount.noise, sensor_seed(o.seed, mount.name + "/noise"));
  std::vector<ImuTruth> truth;
  for (std::size_t k = 0; k < n; ++k) {
    truth.push_back(
        model.measure(scene.imu_truth(static_cast<double>(k) / 400.0, mount.T_body_imu)));
  }
  const SensorClockInverse clock(mount.clock, kEpochNs, (std::int64_t{1} << 32) * 100'000);

  io::SerialCaptureReader reader(o.out_dir / "xsens.serial");
  io::SerialChunk chunk;
  imu::XsensMtData2Decoder decoder;
  std::vector<ImuSample> samples;
  std::size_t torn = 0;
  std::int64_t last_rx = 0;
  while (reader.next(chunk)) {
    EXPECT_GE(chunk.rx_time_ns, last_rx);
    last_rx = chunk.rx_time_ns;
    const auto before = decoder.counters().frames;
    decoder.on_bytes(chunk.bytes, chunk.rx_time_ns,
                     [&](const ImuSample& s) { samples.push_back(s); });
    if (decoder.counters().frames == before) ++torn;  // a read that completed no message
  }
  EXPECT_GT(torn, 100u);
  EXPECT_EQ(samples.size() + rep.dropped, n);
  EXPECT_EQ(decoder.counters().sequence_gaps, rep.dropped);
  EXPECT_GE(decoder.counters().checksum_errors, rep.dropped);
  EXPECT_GT(decoder.counters().skipped_bytes, 0u);
  std::size_t last_k = 0;
  for (const auto& s : samples) {
    // SampleTimeFine (10 kHz ticks of the skewed, offset clock) maps back to the sample time
    // within a tick.
    const double t = clock.scenario_time(s.stamp.sensor.ns, s.stamp.host.ns);
    const auto k = static_cast<std::size_t>(std::llround(t * 400.0));
    ASSERT_LT(k, n);
    EXPECT_NEAR(t, static_cast<double>(k) / 400.0, 100e-6 + 1e-9);
    EXPECT_GE(k, last_k);
    last_k = k;
    // float32 on the wire.
    EXPECT_LE((s.accel_m_s2 - truth[k].accel_m_s2).cwiseAbs().maxCoeff(), 2e-6 * 20.0);
    EXPECT_LE((s.gyro_rad_s - truth[k].gyro_rad_s).cwiseAbs().maxCoeff(), 1e-6);
    // Received after the message was on the wire (45 bytes at 921600 baud = 0.49 ms).
    EXPECT_GT(s.stamp.host.ns,
              kEpochNs + std::llround((static_cast<double>(k) / 400.0 + 0.00048) * 1e9));
  }
}

}  // namespace
}  // namespace livod::sim
