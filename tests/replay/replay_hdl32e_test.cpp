// The Velodyne HDL-32E's internal IMU end to end: `body_frame: <lidar>.imu` through
// `livod replay`, on the simulator's street_vehicle_hdl32e (accuracy against ground truth) and on
// the real monterey capture (what its IMU words really say).
//
// Street target (as the other street scenarios, replay_accuracy_test.cpp): ATE RMSE <= 0.05 % of
// the distance travelled, >= 300 m. The default estimator settings (FAST-LIVO2's avia.yaml)
// reach it with the HDL-32E's own IMU, coarse as it is (12-bit words: 0.0017 rad/s and 0.012
// m/s^2 per LSB; ADIS16080-class gyro noise, five times a BMI088's; a 0.5 rad/s gyro bias taken
// from the real capture): no rig settings are appended.

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "drivers/velodyne/velodyne_decoder.hpp"
#include "io/pcap.hpp"
#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

namespace vel = drivers::velodyne;

constexpr double kStreetAteFraction = 0.0005;  // of the distance travelled
constexpr double kStreetMinPathM = 300.0;
constexpr double kStreetDurationS = 36.0;
constexpr const char* kMonterey = "velodyne/veloview/monterey-first-100-packets.pcap";

struct DecodedCapture {
  std::uint64_t imu_packets = 0;  // the decoder's count of position packets with IMU words
  std::vector<ImuSample> imu;
};

// The capture through livod's Velodyne decoder alone, on its default ports (2368, 8308).
DecodedCapture decode_hdl32e(const std::filesystem::path& pcap,
                             const std::filesystem::path& calibration = {}) {
  vel::VelodyneOptions options;
  options.model = vel::Model::kHdl32e;
  if (!calibration.empty()) options.calibration_file = calibration;
  vel::VelodyneDecoder decoder(options);
  io::PcapReader reader(pcap);
  reader.set_port_filter(decoder.default_ports());
  DecodedCapture out;
  drivers::DecoderSinks sinks;
  sinks.on_imu = [&](const ImuSample& m) { out.imu.push_back(m); };
  while (const auto d = reader.next()) {
    decoder.on_packet({d->payload, d->capture_time_ns, d->dst_port}, sinks);
  }
  decoder.flush(sinks);
  out.imu_packets = decoder.counters().imu_packets;
  return out;
}

const daemon::replay::SensorSummary& only_sensor(const daemon::replay::ReplaySummary& s) {
  EXPECT_EQ(s.sensors.size(), 1u);
  return s.sensors.at(0);
}

// The number the initialiser reports after "<key> " in its status, e.g. "|g| measured 9.4".
double number_after(const std::string& status, const std::string& key) {
  const auto at = status.find(key);
  if (at == std::string::npos) {
    ADD_FAILURE() << "no '" << key << "' in: " << status;
    return 0.0;
  }
  return std::stod(status.substr(at + key.size()));
}

TEST(ReplayHdl32e, StreetVehicleOnTheInternalImuMeetsTheStreetTarget) {
  const sim::Scenario scenario = sim::make_scenario("street_vehicle_hdl32e");
  ASSERT_TRUE(test::scenario_runnable(scenario));
  const auto run = test::simulate_replay_evaluate(scenario, kStreetDurationS, "");
  const auto& s = run.result.summary;
  ASSERT_GT(s.frames, 0U);
  const auto& folder = run.folder;
  const auto& ev = run.eval;
  const double path = run.path_m;
  RecordProperty("ate_rmse_m", std::to_string(ev.ape.rmse));
  RecordProperty("path_m", std::to_string(path));

  // The body is the HDL-32E's own IMU: one stream feeds the estimator its scans and every IMU
  // sample the position packets carried, and the LiDAR's clock model.
  const auto& sensor = only_sensor(s);
  EXPECT_EQ(sensor.name, "hdl32e");
  EXPECT_EQ(sensor.role, "lidar + body imu");
  const DecodedCapture capture = decode_hdl32e(folder / "hdl32e.pcap");
  EXPECT_NEAR(static_cast<double>(capture.imu_packets), kStreetDurationS / 4.988e-3, 1.0);
  EXPECT_EQ(sensor.imu_samples, capture.imu_packets);
  EXPECT_EQ(s.counters.imu_in, capture.imu_packets);
  EXPECT_EQ(sensor.clock.observations, capture.imu_packets);
  EXPECT_EQ(s.init_status.rfind("initialised from", 0), 0U) << s.init_status;

  // Every scan after initialisation became a pose.
  EXPECT_LE(s.counters.scans_out_of_order, 3U);
  EXPECT_EQ(s.counters.scans_queue_overflow, 0U);
  EXPECT_GE(static_cast<double>(s.frames), (kStreetDurationS - 1.0) / 0.1);
  EXPECT_GE(path, kStreetMinPathM);
  EXPECT_LE(ev.ape.rmse, kStreetAteFraction * path);
}

// A small configuration replaying the real monterey capture with its IMU as the body.
std::filesystem::path monterey_config(const std::string& tag, const std::string& source) {
  const auto dir = test::temp_dir("monterey-" + tag);
  const auto path = dir / "monterey.yaml";
  std::ofstream(path)
      << "body_frame: hdl.imu\n"
      << "sensors:\n"
      << "  - name: hdl\n"
      << "    driver: velodyne\n"
      << "    model: HDL-32E\n"
      << "    calibration: " << test::data_path("velodyne/veloview/HDL-32.xml") << "\n"
      << "    source: " << source << "\n"
      << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";
  return path;
}

// What the monterey capture's IMU words really say (1.49 s, 299 position packets): the car
// stands still for its first ~0.3 s and then pulls away (the forward specific force rises from
// 0.45 to about 1.7 m/s^2; the $GPRMC, updated once a second, still says 0 knots). At rest the
// accelerometers read |a| = 9.41 m/s^2, 4 % below gravity: a calibration (scale or bias) error
// of the sensor, not motion (the window passes the static check). The initialiser accepts the
// first 30 samples and says so with the measured |g| and the gyro bias (sensor 3 reads about
// -29 deg/s, 0.51 rad/s about z). Every IMU sample reaches the clock domain and the estimator.
TEST(ReplayHdl32e, RealMontereyCaptureFeedsEveryImuSampleToTheEstimator) {
  const auto pcap = test::data_path(kMonterey);
  const DecodedCapture capture =
      decode_hdl32e(pcap, test::data_path("velodyne/veloview/HDL-32.xml"));
  ASSERT_EQ(capture.imu_packets, 299U);
  ASSERT_EQ(capture.imu.size(), 299U);

  const auto config = monterey_config("config", "{replay: {file: " + pcap.string() + "}}");
  const auto result = test::replay(config, config.parent_path() / "out");
  const auto& s = result.summary;
  const auto& sensor = only_sensor(s);
  EXPECT_EQ(sensor.role, "lidar + body imu");
  EXPECT_EQ(sensor.imu_samples, capture.imu_packets);
  EXPECT_EQ(sensor.clock.observations, capture.imu_packets);
  EXPECT_EQ(s.counters.imu_in, capture.imu_packets);
  EXPECT_EQ(s.counters.imu_out_of_order, 0U);

  // The data: the first 30 samples are still and read 4 % low.
  Eigen::Vector3d window_mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < 30; ++i) window_mean += capture.imu[i].accel_m_s2;
  window_mean /= 30.0;
  EXPECT_NEAR(window_mean.norm(), 9.41, 0.03);
  EXPECT_GT(window_mean.z(), 9.3);  // gravity on +z: the sensor stands upright
  // The estimator: initialised from exactly that window.
  EXPECT_EQ(s.init_status.rfind("initialised from 30 static samples", 0), 0U) << s.init_status;
  EXPECT_NEAR(number_after(s.init_status, "|g| measured "), window_mean.norm(), 1e-3)
      << s.init_status;
  const std::string bias = s.init_status.substr(s.init_status.find("gyro bias ") + 10);
  double bx = 0.0, by = 0.0, bz = 0.0;
  ASSERT_EQ(std::sscanf(bias.c_str(), "%lf %lf %lf", &bx, &by, &bz), 3) << s.init_status;
  EXPECT_NEAR(bz, 0.51, 0.01);
  EXPECT_LT(std::hypot(bx, by), 0.15);

  // The car pulls away: forward specific force over the last 0.5 s against the first 0.3 s.
  const auto mean_forward = [&](std::size_t begin, std::size_t end) {
    double sum = 0.0;
    for (std::size_t i = begin; i < end; ++i) sum += capture.imu[i].accel_m_s2.x();
    return sum / static_cast<double>(end - begin);
  };
  const double start = mean_forward(0, 60);
  const double end = mean_forward(199, 299);
  EXPECT_LT(start, 0.7);
  EXPECT_GT(end - start, 1.0) << start << " -> " << end;
  // ... and the LiDAR-inertial estimate moves forward with it (+x, tens of centimetres).
  ASSERT_GE(s.frames, 10U) << s.init_status;
  std::ifstream trajectory(result.trajectory);
  std::string line;
  double t = 0.0, x = 0.0, y = 0.0, z = 0.0;
  double x_first = 0.0;
  bool first = true;
  while (std::getline(trajectory, line)) {
    if (line.empty() || line[0] == '#') continue;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf %lf %lf %lf", &t, &x, &y, &z), 4) << line;
    if (first) x_first = x;
    first = false;
  }
  EXPECT_GT(x - x_first, 0.15);
  EXPECT_LT(x - x_first, 1.0);
}

// A live-configured HDL-32E replayed from a capture given on the command line keeps its
// configured ports as the pcap filter: the position port, and with it the IMU, is among them.
TEST(ReplayHdl32e, ReplayKeepsThePositionPortThatCarriesTheImu) {
  const auto pcap = test::data_path(kMonterey);
  const std::vector<std::string> inputs = {"hdl=" + pcap.string()};
  {
    const auto config = monterey_config("udp", "{udp: {}}");
    const auto result = test::replay(config, config.parent_path() / "out", inputs);
    const auto& sensor = only_sensor(result.summary);
    EXPECT_EQ(sensor.imu_samples, 299U);
    EXPECT_GT(result.summary.frames, 0U);
  }
  {
    // The sensor configured to send its position packets elsewhere: this capture's are filtered
    // out, no IMU sample arrives and the estimator never initialises.
    const auto config = monterey_config("udp-moved", "{udp: {ports: {position: 8309}}}");
    const auto result = test::replay(config, config.parent_path() / "out", inputs);
    const auto& sensor = only_sensor(result.summary);
    EXPECT_EQ(sensor.imu_samples, 0U);
    EXPECT_EQ(result.summary.frames, 0U);
    EXPECT_NE(sensor.counters.find("other ports 299"), std::string::npos) << sensor.counters;
  }
}

}  // namespace
}  // namespace livod
