// The files the runner writes read back with livod's own readers and decoders and agree with what
// was simulated: the pcap decodes to the simulated points, groundtruth.txt is the trajectory, the
// CAN IMU log holds the IMU model's samples within the CAN quantisation, and the camera folder is
// a valid EuRoC folder with the exposure column and the rendered images.

#include <gtest/gtest.h>

#include <algorithm>

#include "drivers/imu/candump_frames.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "io/candump.hpp"
#include "io/euroc.hpp"
#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/bag_output.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/runner.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

constexpr double kEpoch = 1'700'000'000.0;
constexpr std::int64_t kEpochNs = 1'700'000'000'000'000'000;

std::int64_t to_ns(double s) {
  return static_cast<std::int64_t>(std::llround(s * 1e9));
}

SimRunOptions options_for(const std::string& dir, std::uint64_t seed, double duration) {
  SimRunOptions o;
  o.out_dir = test::temp_dir(dir);
  o.seed = seed;
  o.duration_s = duration;
  o.host_epoch_s = kEpoch;
  o.write_images = false;
  return o;
}

struct TimedPoint {
  double t = 0.0;  // any clock, monotonic in the true time
  Eigen::Vector3f p;
};

TEST(RunnerOutputs, PcapDecodesToTheSimulatedPoints) {
  // Without moving people and potted plants: the test re-simulates the static room world.
  Scenario scenario = make_scenario("room_handheld_avia");
  scenario.scene = SceneContent{};
  const SimRunOptions o = options_for("runner_pcap", 5, 1.5);
  run_scenario(scenario, o);

  // The same LiDAR simulated in memory, in the runner's chunks (the link draws its delays in
  // emission order, which the chunking sets).
  const World world = make_room_world(o.seed);
  const Trajectory trajectory(scenario.trajectory);
  const LidarMount& mount = scenario.lidars.at(0);
  SimLidarOptions lo;
  lo.range = mount.range;
  lo.clock = mount.clock;
  lo.link = mount.link;
  lo.imu = mount.imu;
  lo.imu_noise = mount.imu_noise;
  lo.seed = sensor_seed(o.seed, mount.name);
  lo.host_epoch_s = kEpoch;
  auto lidar = make_sim_lidar(mount.model, lo);
  SceneContext scene{&world, &trajectory, mount.T_body_sensor};
  std::vector<SimDatagram> datagrams;
  std::vector<TimedPoint> expected;
  SimOutputs out;
  out.on_datagram = [&](SimDatagram&& d) { datagrams.push_back(std::move(d)); };
  out.on_point = [&](const SimPointTruth& p) {
    if (p.valid) expected.push_back({p.t, p.p_sensor.cast<float>()});
  };
  for (double t = 0.0; t < *o.duration_s; t += o.chunk_s) {
    lidar->run(t, std::min(*o.duration_s, t + o.chunk_s), scene, out);
  }
  std::stable_sort(datagrams.begin(), datagrams.end(),
                   [](const auto& a, const auto& b) { return a.host_time_ns < b.host_time_ns; });

  io::PcapReader reader(o.out_dir / "avia.pcap");
  livox::LivoxDecoder decoder(*livox::livox_model("AVIA"), livox::LivoxDecoderOptions{});
  std::vector<TimedPoint> decoded;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    for (std::size_t i = 0; i < s.size(); ++i) {
      decoded.push_back({static_cast<double>(s.start.sensor.ns + s.t_offset_ns[i]), s.point(i)});
    }
  };
  std::size_t n = 0;
  while (const auto d = reader.next()) {
    ASSERT_LT(n, datagrams.size());
    // Arrival order, receive stamps and payloads are the simulated link's.
    EXPECT_EQ(d->capture_time_ns, datagrams[n].host_time_ns) << "datagram " << n;
    EXPECT_EQ(d->src_port, datagrams[n].src_port);
    EXPECT_EQ(d->dst_port, datagrams[n].dst_port);
    ASSERT_TRUE(std::equal(d->payload.begin(), d->payload.end(), datagrams[n].payload.begin(),
                           datagrams[n].payload.end()))
        << "datagram " << n;
    decoder.on_packet({d->payload, d->capture_time_ns, d->dst_port}, sinks);
    ++n;
  }
  decoder.flush(sinks);
  EXPECT_EQ(n, datagrams.size());
  EXPECT_EQ(reader.stats().malformed, 0u);
  EXPECT_EQ(decoder.counters().decode_errors, 0u);

  // A delay spike can reorder datagrams: compare in point-time order. A packet that arrives after
  // the scan it belongs to was emitted is dropped and counted by the decoder (late points): every
  // decoded point is a simulated one, and the simulated ones missing are exactly the late ones.
  const auto by_time = [](const TimedPoint& a, const TimedPoint& b) { return a.t < b.t; };
  std::stable_sort(decoded.begin(), decoded.end(), by_time);
  std::stable_sort(expected.begin(), expected.end(), by_time);
  ASSERT_GT(expected.size(), 200'000u);  // 1.5 s at 240 kpts/s, most with a return
  ASSERT_EQ(decoded.size() + decoder.counters().late_points, expected.size());
  EXPECT_LT(decoder.counters().late_points, expected.size() / 1000);
  std::size_t d = 0;
  for (std::size_t e = 0; e < expected.size() && d < decoded.size(); ++e) {
    if (decoded[d].p == expected[e].p) ++d;  // times differ in clock (sensor vs scenario)
  }
  EXPECT_EQ(d, decoded.size()) << "decoded point " << d << " was not simulated";
}

TEST(RunnerOutputs, GroundTruthIsTheTrajectoryInTumFormat) {
  const Scenario scenario = make_scenario("room_handheld_avia");
  const SimRunOptions o = options_for("runner_groundtruth", 2, 1.2);
  Scenario trajectory_only = scenario;  // the sensors add nothing to this check
  trajectory_only.lidars.clear();
  trajectory_only.cameras.clear();
  run_scenario(trajectory_only, o);
  const auto poses = io::read_tum_trajectory(o.out_dir / "groundtruth.txt");
  ASSERT_EQ(poses.size(), static_cast<std::size_t>(1.2 * scenario.groundtruth_rate_hz) + 1);
  const Trajectory trajectory(scenario.trajectory);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    // Stamps are exact: host epoch + k / rate, to the nanosecond.
    const std::int64_t t_ns = to_ns(static_cast<double>(k) / scenario.groundtruth_rate_hz);
    ASSERT_EQ(poses[k].timestamp.ns, kEpochNs + t_ns) << k;
    const TrajectoryState s = trajectory.at(static_cast<double>(t_ns) * 1e-9);
    EXPECT_LT((poses[k].p_world_body - s.p_world).norm(), 2e-9) << k;  // 9 decimals
    const Eigen::Quaterniond q(s.R_world_body);
    EXPECT_LT(poses[k].q_world_body.angularDistance(q), 4e-9) << k;
  }
}

TEST(RunnerOutputs, CanImuLogHoldsTheImuModelWithinTheCanQuantisation) {
  // Only the CAN IMU: the LiDAR adds nothing to this check.
  Scenario scenario = make_scenario("street_vehicle_vlp16");
  scenario.lidars.clear();
  ASSERT_TRUE(scenario.can_imu);
  // 2 s standing, then accelerating: the samples cover both.
  const SimRunOptions o = options_for("runner_can_imu", 9, 3.0);
  run_scenario(scenario, o);

  const CanImuMount& mount = *scenario.can_imu;
  const World world = make_street_world(o.seed, scenario.street_length_m);
  const Trajectory trajectory(scenario.trajectory);
  SceneContext scene{&world, &trajectory};
  ImuModel model(mount.noise, sensor_seed(o.seed, mount.name + "/noise"));
  const double period = 1.0 / mount.noise.rate_hz;
  const auto samples = static_cast<std::size_t>(std::floor(*o.duration_s / period));

  io::CandumpReader reader(o.out_dir / (mount.name + ".log"));
  imu::SbgCanDecoder decoder;
  const SensorClockInverse clock(mount.clock, kEpochNs, kSbgCounterWrapNs);
  io::CanFrame frame;
  std::size_t k = 0;
  double max_accel_error = 0.0;
  double max_gyro_error = 0.0;
  while (reader.next(frame)) {
    std::optional<ImuSample> sample;
    decoder.on_frame(imu::to_can_record(frame), [&](const ImuSample& s) { sample = s; });
    if (!sample) continue;
    ASSERT_LT(k, samples);
    const double t = static_cast<double>(k) * period;
    const ImuTruth m = model.measure(scene.imu_truth(t, mount.T_body_imu));
    // The device counter is whole microseconds of the (offset, skewed) device clock.
    EXPECT_NEAR(clock.scenario_time(sample->stamp.sensor.ns, sample->stamp.host.ns), t, 1.01e-6)
        << k;
    EXPECT_GT(sample->stamp.host.ns, kEpochNs + to_ns(t)) << "received before sent, " << k;
    max_accel_error =
        std::max(max_accel_error, (sample->accel_m_s2 - m.accel_m_s2).cwiseAbs().maxCoeff());
    max_gyro_error =
        std::max(max_gyro_error, (sample->gyro_rad_s - m.gyro_rad_s).cwiseAbs().maxCoeff());
    ++k;
  }
  EXPECT_EQ(k, samples);
  EXPECT_EQ(decoder.counters().malformed, 0u);
  EXPECT_EQ(decoder.counters().incomplete, 0u);
  // Half a count of 0.01 m/s^2 and 0.001 rad/s (round to nearest).
  EXPECT_LE(max_accel_error, 0.005 + 1e-9);
  EXPECT_LE(max_gyro_error, 0.0005 + 1e-9);
  // ... and not exact: the values really went through the quantisation.
  EXPECT_GT(max_accel_error, 0.001);
}

TEST(RunnerOutputs, CameraFolderIsEurocWithExposureAndTheRenderedImages) {
  // Without moving people and potted plants: the test re-simulates the static room world.
  Scenario scenario = make_scenario("room_handheld_avia");
  scenario.scene = SceneContent{};
  SimRunOptions o = options_for("runner_camera", 4, 0.3);
  o.write_images = true;
  run_scenario(scenario, o);
  const CameraMount& cam = scenario.cameras.at(0);

  const io::EurocFolder folder(o.out_dir);
  ASSERT_EQ(folder.cameras(), std::vector<std::string>{cam.name});
  const auto images = folder.images(cam.name);
  ASSERT_EQ(images.size(), 3u);  // 10 Hz, mid-exposure at 0.05, 0.15, 0.25 s
  const CameraSim sim(cam.params);
  const World world = make_room_world(o.seed);
  const Trajectory trajectory(scenario.trajectory);
  std::mt19937_64 rng(sensor_seed(o.seed, cam.name));
  GreyImage expected;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const double t = 0.05 + 0.1 * static_cast<double>(i);
    EXPECT_EQ(images[i].timestamp.ns, kEpochNs + to_ns(t + cam.time_offset_s));
    ASSERT_TRUE(images[i].exposure) << "exposure column missing";
    EXPECT_EQ(images[i].exposure->count(), to_ns(sim.exposure_at(t)));
    // The PNG, read back with livod's image reader, holds exactly the rendered frame (same seed,
    // same order of frames).
    const auto png = load_image_message(images[i], cam.name, 0);
    ASSERT_EQ(png.width, static_cast<std::uint32_t>(cam.params.intrinsics.width));
    ASSERT_EQ(png.height, static_cast<std::uint32_t>(cam.params.intrinsics.height));
    sim.render(world, trajectory.at(t).T_world_body() * cam.T_body_cam, sim.exposure_at(t), rng,
               expected);
    ASSERT_TRUE(png.data == expected.pixels) << "frame " << i;
  }

  const auto calib = folder.camera_calibration(cam.name);
  const auto& k = cam.params.intrinsics;
  EXPECT_EQ(calib.width, k.width);
  EXPECT_EQ(calib.height, k.height);
  EXPECT_DOUBLE_EQ(calib.rate_hz, cam.params.rate_hz);
  EXPECT_NEAR(calib.intrinsics[0], k.fx, 1e-9);
  EXPECT_NEAR(calib.intrinsics[1], k.fy, 1e-9);
  EXPECT_NEAR(calib.intrinsics[2], k.cx, 1e-9);
  EXPECT_NEAR(calib.intrinsics[3], k.cy, 1e-9);
  EXPECT_EQ(calib.distortion_model, io::EurocDistortionModel::kRadialTangential);
  ASSERT_EQ(calib.distortion_coefficients.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(calib.distortion_coefficients[i], k.distortion[i], 1e-12);
  }
  EXPECT_LT((calib.T_body_sensor - cam.T_body_cam.matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

}  // namespace
}  // namespace livod::sim
