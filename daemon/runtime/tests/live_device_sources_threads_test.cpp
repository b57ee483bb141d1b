// The runtime's live camera and IMU sources (live_camera_source.hpp, live_imu_source.hpp) with
// their real capture threads: what the scheduler sees through MeasurementSource. Devices the
// machine lacks (a V4L2 node, a CAN interface, a serial port) do not stop the daemon: they are
// reported by name and retried, and a serial port that appears later streams its Xsens samples.
// (The camera with Aravis's fake: live_camera_source_test.cpp, not under ThreadSanitizer, which
// would report on GLib's uninstrumented internals.)

#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "core/image.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/runtime/live_camera_source.hpp"
#include "daemon/runtime/live_imu_source.hpp"
#include "daemon/runtime/tests/live_source_test_support.hpp"
#include "drivers/imu/xsens_mtdata2.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::runtime {
namespace {

using namespace std::chrono_literals;

using test_support::drain;
using test_support::kExtrinsic;
using test_support::kLidar;
using test_support::load_runnable;

// A configured device the machine lacks: the open fails with a message naming the device, which
// health reports, and the daemon keeps running (the device is retried every second).
TEST(LiveDeviceSources, DevicesTheMachineLacksAreReportedByNameAndRetried) {
  const auto config = load_runnable("body_frame: xsens\nsensors:\n" + kLidar + R"(  - name: xsens
    driver: serial_imu
    source: {device: {path: /dev/ttyLIVOD9}}
    serial: {protocol: xsens_mtdata2, baud_rate: 921600}
)" + kExtrinsic + R"(  - name: bus
    driver: can_imu
    enabled: false                  # the estimator takes one IMU; the source is tested alone
    source: {device: {interface: can7}}
    can: {decoder: bosch_mm7}
)" + kExtrinsic + R"(  - name: front
    driver: v4l2
    source: {device: {path: /dev/video9}}
    camera: {width: 640, height: 480, intrinsics: [500, 500, 320, 240]}
)" + kExtrinsic + "estimator: {vio: {enabled: false}}\n");
  auto serial = open_live_imu(*config.find_sensor("xsens"), config, nullptr);
  auto can = open_live_imu(*config.find_sensor("bus"), config, nullptr);
  auto v4l2 = open_live_camera(*config.find_sensor("front"), config, nullptr);
  const auto check = [](MeasurementSource& s, const std::string& expected) {
    const auto h = s.health(host_now());
    ASSERT_TRUE(h);
    EXPECT_NE(h->last_error.find(expected), std::string::npos) << h->last_error;
    EXPECT_EQ(h->device_state, "OPENING");
    EXPECT_NE(h->streams.at(0).state, drivers::capture::StreamState::kStreaming);
    EXPECT_FALSE(s.peek_time());
    EXPECT_FALSE(s.exhausted()) << "a live source waiting for its device is not finished";
  };
  check(*serial, "serial port /dev/ttyLIVOD9 does not exist");
  check(*can, "SocketCAN interface 'can7'");
  check(*v4l2, "V4L2 device /dev/video9: does not exist");
  // Retried: the capture threads keep trying (and keep beating for the watchdog).
  const auto beats = serial->threads().at(0).beats();
  std::this_thread::sleep_for(1500ms);
  EXPECT_GT(serial->threads().at(0).beats(), beats);
  EXPECT_NE(serial->summary().find("opens 0"), std::string::npos) << serial->summary();
  for (auto* s : {serial.get(), can.get(), v4l2.get()}) {
    s->stop();
    EXPECT_TRUE(s->exhausted());
  }
}

// The serial port appears after start (a USB adapter enumerating late): the source opens it and
// its Xsens samples reach the sinks with sensor and host stamps.
TEST(LiveDeviceSources, ASerialImuThatAppearsLateStreams) {
  const auto dir = test::temp_dir("live_imu_late");
  const auto link = dir / "mti";
  std::filesystem::remove(link);
  const auto config = load_runnable("body_frame: mti\nsensors:\n" + kLidar + R"(  - name: mti
    driver: serial_imu
    source: {device: {path: )" + link.string() +
                                    R"(}}
    serial: {protocol: xsens_mtdata2, baud_rate: 921600}
)" + kExtrinsic);
  drivers::capture::Doorbell doorbell;
  auto source = open_live_imu(*config.find_sensor("mti"), config, &doorbell);
  EXPECT_FALSE(source->delivers_mapped_images());
  EXPECT_EQ(source->threads().at(0).name, "mti.serial");

  int master = -1;
  int slave = -1;
  ASSERT_EQ(::openpty(&master, &slave, nullptr, nullptr, nullptr), 0);
  const std::string name = ::ttyname(slave);
  ::close(slave);
  std::filesystem::create_symlink(name, link);
  // Opened within the retry interval.
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (source->health(host_now())->device_state != "STREAMING" &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_EQ(source->health(host_now())->device_state, "STREAMING");
  std::vector<std::uint8_t> bytes;
  for (int k = 0; k < 40; ++k) {
    imu::XsensSample x;
    x.packet_counter = static_cast<std::uint16_t>(k);
    x.sample_time_fine = static_cast<std::uint32_t>(25 * k);
    x.accel_m_s2 = Eigen::Vector3d(0.0, 0.0, 9.81);
    x.gyro_rad_s = Eigen::Vector3d(0.01 * k, 0.0, 0.0);
    const auto m = imu::encode_mtdata2_sample(x);
    bytes.insert(bytes.end(), m.begin(), m.end());
  }
  ASSERT_EQ(::write(master, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  std::vector<ImuSample> samples;
  drivers::DecoderSinks sinks;
  sinks.on_imu = [&](const ImuSample& s) { samples.push_back(s); };
  ASSERT_TRUE(drain(*source, sinks, [&] { return samples.size() == 40; })) << samples.size();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    EXPECT_EQ(samples[k].stamp.sensor.ns, static_cast<std::int64_t>(25 * k) * 100'000);
    EXPECT_GT(samples[k].stamp.host.ns, 0);
    EXPECT_NEAR(samples[k].gyro_rad_s.x(), 0.01 * static_cast<double>(k), 1e-6);
  }
  const auto h = source->health(host_now());
  EXPECT_EQ(h->reconnects, 0u);
  EXPECT_EQ(h->decoder.decode_errors, 0u);
  source->stop();
  ::close(master);
}

}  // namespace
}  // namespace livod::daemon::runtime
