// Decoding the simulator's Velodyne captures with livod's Velodyne decoder gives back the
// simulated points (2 mm quantisation is applied by the simulator; float rounding remains) at
// their firing times, and, for the HDL-32E, the simulated IMU samples within the quantisation of
// the position packets' 12-bit words, at the packets' real rates.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "drivers/velodyne/position_packet.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

namespace vel = drivers::velodyne;

constexpr std::int64_t kHourNs = 3'600'000'000'000LL;
constexpr std::uint16_t kDataPort = 2368;
constexpr std::uint16_t kPositionPort = 8308;
// Half an LSB of the HDL-32E motion words, in SI (position_packet.hpp scale factors).
constexpr double kHalfGyroLsbRadS = 0.5 * vel::kHdlGyroDegPerSecPerLsb * std::numbers::pi / 180.0;
constexpr double kHalfAccelLsbMS2 = 0.5 * vel::kHdlAccelGPerLsb * kStandardGravity;

struct Capture {
  std::vector<SimDatagram> datagrams;
  std::vector<SimPointTruth> points;
  std::vector<SimImuTruth> imu;
};

struct Decoded {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::int64_t> point_ns;  // sensor clock
  std::vector<ImuSample> imu;
  std::uint64_t scans = 0;
};

// One LiDAR of a named scenario, simulated over [t_begin, t_end) as the runner would (same
// options), datagrams in emission order.
class VelodyneRun {
 public:
  explicit VelodyneRun(const std::string& scenario_name)
      : scenario_(make_scenario(scenario_name)),
        world_(make_street_world(1, scenario_.street_length_m)),
        trajectory_(scenario_.trajectory),
        mount_(scenario_.lidars.at(0)) {
    options_.clock = mount_.clock;
    options_.range = mount_.range;
    options_.imu = mount_.imu;
    options_.imu_noise = mount_.imu_noise;
    options_.seed = 5;
  }

  Capture simulate(double t_begin, double t_end) const {
    auto lidar = make_sim_lidar(mount_.model, options_);
    EXPECT_EQ(lidar->model(), mount_.model);
    const SceneContext scene{&world_, &trajectory_, mount_.T_body_sensor};
    Capture c;
    SimOutputs out;
    out.on_datagram = [&](SimDatagram&& d) { c.datagrams.push_back(std::move(d)); };
    out.on_point = [&](const SimPointTruth& p) { c.points.push_back(p); };
    out.on_imu = [&](const SimImuTruth& m) { c.imu.push_back(m); };
    lidar->run(t_begin, t_end, scene, out);
    return c;
  }

  // The sensor clock the simulator stamped with (no jitter in the scenarios: deterministic).
  [[nodiscard]] std::int64_t sensor_ns(double t) const {
    SensorClock clock(mount_.clock, 0);
    return clock.stamp_ns(t);
  }

  [[nodiscard]] const LidarMount& mount() const { return mount_; }
  [[nodiscard]] const Trajectory& trajectory() const { return trajectory_; }

 private:
  Scenario scenario_;
  World world_;
  Trajectory trajectory_;
  LidarMount mount_;
  SimLidarOptions options_;
};

Decoded decode(vel::VelodyneDecoder& decoder, const Capture& capture) {
  Decoded d;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    ++d.scans;
    for (std::size_t i = 0; i < s.size(); ++i) {
      d.points.push_back(s.point(i));
      d.point_ns.push_back(s.start.sensor.ns + s.t_offset_ns[i]);
    }
  };
  sinks.on_imu = [&](const ImuSample& m) { d.imu.push_back(m); };
  for (const auto& g : capture.datagrams) {
    decoder.on_packet({g.payload, g.host_time_ns, g.dst_port}, sinks);
  }
  decoder.flush(sinks);
  return d;
}

// a - b on a top-of-hour timeline: the decoder picks the hour from the receive time, the
// simulated clock counts from its own offset.
std::int64_t within_hour(std::int64_t a, std::int64_t b) {
  std::int64_t d = (a - b) % kHourNs;
  if (d > kHourNs / 2) d -= kHourNs;
  if (d < -kHourNs / 2) d += kHourNs;
  return d;
}

// Every simulated return decodes to its ray-cast point and firing time.
void expect_points_decode_exactly(const VelodyneRun& run, const Capture& capture,
                                  const Decoded& decoded) {
  std::vector<const SimPointTruth*> expected;
  for (const auto& t : capture.points) {
    if (t.valid) expected.push_back(&t);
  }
  ASSERT_GT(expected.size(), capture.points.size() / 3);
  ASSERT_EQ(decoded.points.size(), expected.size());
  double worst_m = 0.0;
  std::int64_t worst_ns = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    worst_m = std::max(
        worst_m,
        static_cast<double>((decoded.points[i] - expected[i]->p_sensor.cast<float>()).norm()));
    const std::int64_t dt = within_hour(decoded.point_ns[i], run.sensor_ns(expected[i]->t));
    worst_ns = std::max(worst_ns, std::abs(dt));
  }
  EXPECT_LT(worst_m, 1e-4);
  // Packet stamps are whole microseconds (truncated) of the sensor clock; the firing offsets
  // are nominal durations, off by the clock skew (25 ppm of 1.3 ms: 33 ns).
  EXPECT_LE(worst_ns, 1050);
}

TEST(VelodyneSim, Vlp16CaptureDecodesToTheSimulatedPoints) {
  const VelodyneRun run("street_vehicle_vlp16");
  const Capture capture = run.simulate(8.0, 8.25);  // driving at 10 m/s
  ASSERT_FALSE(capture.datagrams.empty());
  vel::VelodyneOptions vo;
  vo.model = vel::Model::kVlp16;
  vel::VelodyneDecoder decoder(vo);
  const Decoded decoded = decode(decoder, capture);
  EXPECT_EQ(decoder.counters().decode_errors, 0u);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0u);
  EXPECT_GT(decoder.velodyne_counters().position_packets, 1u);
  EXPECT_EQ(decoder.counters().imu_packets, 0u);  // a VLP-16 has no IMU
  EXPECT_GE(decoder.counters().scans, 2u);        // 0.25 s at 10 Hz crosses at least two cuts
  EXPECT_TRUE(capture.imu.empty());
  expect_points_decode_exactly(run, capture, decoded);
}

TEST(VelodyneSim, Hdl32eCaptureDecodesToTheSimulatedPointsAndImu) {
  const VelodyneRun run("street_vehicle_hdl32e");
  ASSERT_EQ(run.mount().model, "HDL-32E");
  const Capture capture = run.simulate(8.0, 8.25);
  ASSERT_FALSE(capture.datagrams.empty());
  vel::VelodyneOptions vo;
  vo.model = vel::Model::kHdl32e;  // the built-in calibration, as `livod decode --model HDL-32E`
  vel::VelodyneDecoder decoder(vo);
  const Decoded decoded = decode(decoder, capture);
  EXPECT_EQ(decoder.counters().decode_errors, 0u);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0u);
  EXPECT_EQ(decoder.velodyne_counters().factory_byte_mismatches, 0u);
  EXPECT_GE(decoder.counters().scans, 2u);
  expect_points_decode_exactly(run, capture, decoded);

  // 32 rings, as the calibration's elevations rank them.
  std::vector<bool> ring_seen(32, false);
  for (const auto& p : capture.points) {
    ASSERT_LT(p.ring, 32u);
    ring_seen[p.ring] = true;
  }
  EXPECT_EQ(std::count(ring_seen.begin(), ring_seen.end(), true), 32);

  // IMU: one sample per position packet, the simulated values within half an LSB per axis, at
  // the position packet's stamp.
  ASSERT_FALSE(capture.imu.empty());
  ASSERT_EQ(decoded.imu.size(), capture.imu.size());
  EXPECT_EQ(decoder.counters().imu_packets, capture.imu.size());
  double worst_gyro = 0.0;
  double worst_accel = 0.0;
  for (std::size_t i = 0; i < decoded.imu.size(); ++i) {
    const auto& got = decoded.imu[i];
    const auto& truth = capture.imu[i];
    worst_gyro = std::max(worst_gyro, (got.gyro_rad_s - truth.gyro_rad_s).cwiseAbs().maxCoeff());
    worst_accel = std::max(worst_accel, (got.accel_m_s2 - truth.accel_m_s2).cwiseAbs().maxCoeff());
    const std::int64_t dt = within_hour(got.stamp.sensor.ns, run.sensor_ns(truth.t));
    EXPECT_GE(dt, -1000);
    EXPECT_LE(dt, 0);  // whole microseconds, truncated
  }
  EXPECT_LE(worst_gyro, kHalfGyroLsbRadS * (1 + 1e-9));
  EXPECT_LE(worst_accel, kHalfAccelLsbMS2 * (1 + 1e-9));
  // Quantisation is what is left: the words are not coarser than one LSB.
  EXPECT_GT(worst_gyro, 0.25 * kHalfGyroLsbRadS);
}

// At rest the decoded IMU reads gravity up the LiDAR's z axis and the simulated gyro biases: the
// axis conventions agree with the decoder's, independently of the simulator's own truth.
TEST(VelodyneSim, Hdl32eAtRestReadsGravityUpAndTheGyroBias) {
  const VelodyneRun run("street_vehicle_hdl32e");
  const Capture capture = run.simulate(0.5, 1.5);  // the vehicle stands still for 2 s
  vel::VelodyneOptions vo;
  vo.model = vel::Model::kHdl32e;
  vel::VelodyneDecoder decoder(vo);
  const Decoded decoded = decode(decoder, capture);
  ASSERT_GE(decoded.imu.size(), 190u);
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  for (const auto& m : decoded.imu) {
    accel += m.accel_m_s2;
    gyro += m.gyro_rad_s;
  }
  accel /= static_cast<double>(decoded.imu.size());
  gyro /= static_cast<double>(decoded.imu.size());
  const Eigen::Matrix3d R_world_sensor =
      run.trajectory().at(1.0).R_world_body * run.mount().T_body_sensor.linear();
  const Eigen::Vector3d up =
      R_world_sensor.transpose() * Eigen::Vector3d(0, 0, 9.81) + run.mount().imu_noise.accel_bias0;
  EXPECT_GT(accel.z(), 9.7);
  EXPECT_LT((accel - up).norm(), 0.02) << accel.transpose();
  EXPECT_LT((gyro - run.mount().imu_noise.gyro_bias0).norm(), 0.005) << gyro.transpose();
}

// Packet rates of the real sensor: 1808 data packets per second (12 x 46.08 us each) and one
// position packet every 4.988 ms (the monterey capture's mean), all from the sensor's address.
TEST(VelodyneSim, Hdl32ePacketRatesAreTheRealOnes) {
  const VelodyneRun run("street_vehicle_hdl32e");
  const Capture capture = run.simulate(3.05, 4.05);
  std::size_t data = 0;
  std::size_t position = 0;
  for (const auto& d : capture.datagrams) {
    if (d.dst_port == kDataPort && d.payload.size() == 1206) ++data;
    if (d.dst_port == kPositionPort && d.payload.size() == 512) {
      ++position;
      EXPECT_EQ(d.src_port, kPositionPort);
    }
  }
  EXPECT_EQ(data + position, capture.datagrams.size());
  EXPECT_NEAR(static_cast<double>(data), 1e6 / (12 * 46.08), 1.0);
  EXPECT_NEAR(static_cast<double>(position), 1.0 / 4.988e-3, 1.0);
  EXPECT_EQ(capture.imu.size(), position);
  // Ten turns per second: every turn is a scan of the azimuth cut.
  vel::VelodyneOptions vo;
  vo.model = vel::Model::kHdl32e;
  vel::VelodyneDecoder decoder(vo);
  const Decoded decoded = decode(decoder, capture);
  EXPECT_EQ(decoded.scans, 11u);  // 10 cuts at the turns 3.1 .. 4.0 s
}

TEST(VelodyneSim, Hdl32eWithoutImuSendsEmptyMotionWords) {
  const Scenario scenario = make_scenario("street_vehicle_hdl32e");
  SimLidarOptions options;
  options.imu = false;
  auto lidar = make_sim_lidar("HDL-32E", options);
  const World world = make_street_world(1, scenario.street_length_m);
  const Trajectory trajectory(scenario.trajectory);
  const SceneContext scene{&world, &trajectory, Eigen::Isometry3d::Identity()};
  std::vector<SimDatagram> datagrams;
  std::size_t truths = 0;
  SimOutputs out;
  out.on_datagram = [&](SimDatagram&& d) { datagrams.push_back(std::move(d)); };
  out.on_imu = [&](const SimImuTruth&) { ++truths; };
  lidar->run(0.0, 0.1, scene, out);
  vel::VelodyneOptions vo;
  vo.model = vel::Model::kHdl32e;
  vel::VelodyneDecoder decoder(vo);
  drivers::DecoderSinks sinks;
  for (const auto& d : datagrams) decoder.on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  EXPECT_EQ(truths, 0u);
  EXPECT_EQ(decoder.counters().imu_packets, 0u);
  EXPECT_EQ(decoder.velodyne_counters().position_packets, 21u);
}

}  // namespace
}  // namespace livod::sim
