// Live sources built from the configuration: a configured device the machine lacks fails at open
// with a message naming the sensor and the device; a configured Aravis camera (Aravis's fake)
// streams; the custom CAN decoder described in YAML decodes a candump log in replay.

#include "daemon/devices/device_sources.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/error.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/devices/imu_decoders.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "drivers/camera/aravis_camera.hpp"
#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/candump_frames.hpp"
#include "io/candump.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

using namespace std::chrono_literals;

// A configuration with no error but "not implemented": check-config rejects live cameras and
// IMUs because the runtime does not start them yet; the device sources tested here are what it
// will start. Warnings (a camera unused while the visual update is off) are not errors.
LivodConfig load_ok(const std::string& yaml) {
  auto r = load_config_from_string(yaml, "test.yaml");
  std::string problems;
  for (const auto& p : r.problems) {
    if (p.kind != ProblemKind::not_implemented && p.severity == Severity::error) {
      problems += format_problem(r.source, p) + "\n";
    }
  }
  EXPECT_TRUE(problems.empty()) << problems;
  return r.config;
}

const std::string kLidar = R"(  - {name: vlp, driver: velodyne, model: VLP-16, source: {udp: {}},
     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}
)";
const std::string kExtrinsic =
    "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";

std::string open_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "opened";
}

TEST(DeviceSources, DevicesTheMachineLacksFailAtOpenNamingSensorAndDevice) {
  const auto config = load_ok("body_frame: xsens\nsensors:\n" + kLidar + R"(  - name: xsens
    driver: serial_imu
    source: {device: {path: /dev/ttyLIVOD9}}
    serial: {protocol: xsens_mtdata2, baud_rate: 921600}
  - name: bus
    driver: can_imu
    source: {device: {interface: livodcan3}}
    can: {decoder: bosch_mm7}
)" + kExtrinsic + R"(  - name: front
    driver: v4l2
    source: {device: {path: /dev/video42}}
    camera: {width: 640, height: 480, intrinsics: [500, 500, 320, 240]}
)" + kExtrinsic + R"(  - name: gige
    driver: aravis
    source: {device: {camera_id: Basler-acA2440-20gm-1234}}
    camera: {width: 640, height: 480, intrinsics: [500, 500, 320, 240]}
)" + kExtrinsic);
  const auto e1 =
      open_error([&] { devices::open_serial_imu_source(*config.find_sensor("xsens"), config); });
  EXPECT_NE(e1.find("sensor 'xsens': serial port /dev/ttyLIVOD9 does not exist"), std::string::npos)
      << e1;
  const auto e2 =
      open_error([&] { devices::open_can_imu_source(*config.find_sensor("bus"), config); });
  EXPECT_NE(e2.find("sensor 'bus': SocketCAN interface 'livodcan3'"), std::string::npos) << e2;
  const auto e3 =
      open_error([&] { devices::open_camera_source(*config.find_sensor("front"), config); });
  EXPECT_EQ(e3, "sensor 'front': V4L2 device /dev/video42: does not exist");
  const auto e4 =
      open_error([&] { devices::open_camera_source(*config.find_sensor("gige"), config); });
  EXPECT_NE(e4.find("sensor 'gige': Aravis camera 'Basler-acA2440-20gm-1234' not found"),
            std::string::npos)
      << e4;
  // Clock modes of the IMUs with clock.mode auto.
  EXPECT_EQ(devices::imu_clock_mode(*config.find_sensor("xsens")), livod::ClockMode::free_running);
  EXPECT_EQ(devices::imu_clock_mode(*config.find_sensor("bus")), livod::ClockMode::receive_time);
}

TEST(DeviceSources, AConfiguredAravisCameraStreams) {
  camera::AravisCamera::enable_fake_interface();
  const auto config = load_ok("body_frame: xs\nsensors:\n" + kLidar + R"(  - name: xs
    driver: serial_imu
    source: {device: {path: /dev/ttyUSB0}}
    serial: {protocol: xsens_mtdata2}
  - name: cam
    driver: aravis
    source: {device: {camera_id: Fake_1}}
    time_offset_s: 0.002
    camera: {width: 320, height: 240, intrinsics: [300, 300, 160, 120], exposure_s: 0.004,
             frame_rate_hz: 40, pixel_format: mono8, buffers: 4, decimation: 2}
)" + kExtrinsic + "estimator: {vio: {enabled: false}}\n");
  auto source = devices::open_camera_source(*config.find_sensor("cam"), config);
  std::vector<camera::FrameInfo> infos;
  const auto deadline = std::chrono::steady_clock::now() + 15s;
  while (infos.size() < 6 && std::chrono::steady_clock::now() < deadline) {
    source->poll([&](const camera::CameraFrame& f) { infos.push_back(f.info); });
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_GE(infos.size(), 6u);
  EXPECT_EQ(infos[0].exposure, 4ms);
  EXPECT_EQ(infos[1].sequence - infos[0].sequence, 2u);  // decimation 2
  EXPECT_GT(source->update_health(host_now()).decimated, 0u);
}

// The os0-custom-can-imu example describes an MM7 with the custom decoder: the replay source
// built from it decodes a candump log of MM7 frames to the Bosch decoder's values (roll sign
// included: the example negates it with factor -0.005).
TEST(DeviceSources, TheCustomCanDecoderFromYamlDecodesACandumpLog) {
  const auto config = load_ok("body_frame: can\nsensors:\n" + kLidar + R"(  - name: can
    driver: can_imu
    source: {device: {interface: can0}}
    can:
      decoder: custom
      sample_id: 0x17C
      signals:
        - {quantity: gyro_z,  id: 0x174, start_bit: 0,  length: 16, factor: 0.005,       offset: -163.84, unit: deg_s}
        - {quantity: accel_y, id: 0x174, start_bit: 32, length: 16, factor: 0.000127465, offset: -4.1768, unit: g}
        - {quantity: gyro_x,  id: 0x178, start_bit: 0,  length: 16, factor: -0.005,      offset: 163.84,  unit: deg_s}
        - {quantity: accel_x, id: 0x178, start_bit: 32, length: 16, factor: 0.000127465, offset: -4.1768, unit: g}
        - {quantity: gyro_y,  id: 0x17C, start_bit: 0,  length: 16, factor: 0.005,       offset: -163.84, unit: deg_s}
        - {quantity: accel_z, id: 0x17C, start_bit: 32, length: 16, factor: 0.000127465, offset: -4.1768, unit: g}
)");
  const auto log = test::temp_dir("custom_can_replay") / "mm7.log";
  std::vector<ImuSample> truth;
  {
    io::CandumpWriter w(log);
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d a(0.1 * k, -0.2, 9.8);
      const Eigen::Vector3d g(0.01 * k, -0.3, 0.05);
      auto frames = imu::encode_bosch_mm7_sample(static_cast<std::uint8_t>(k & 15), a, g, 30.0);
      for (std::size_t f = 0; f < 3; ++f) {
        frames[f].rx_time_ns =
            1'700'000'000'000'000'000 + k * 10'000'000 + static_cast<std::int64_t>(f) * 232'000;
        w.write(imu::to_candump_frame(frames[f], "can0"));
      }
      imu::BoschMm7Decoder ref;
      for (const auto& f : frames) ref.on_frame(f, [&](const ImuSample& s) { truth.push_back(s); });
    }
    w.flush();
  }
  auto source = replay::make_candump_source(log, config.find_sensor("can")->can, "can");
  std::vector<ImuSample> got;
  drivers::DecoderSinks sinks;
  sinks.on_imu = [&](const ImuSample& s) { got.push_back(s); };
  while (source->peek_time()) source->deliver(sinks);
  ASSERT_EQ(got.size(), 50u) << source->summary();
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_LT((got[k].accel_m_s2 - truth[k].accel_m_s2).norm(), 1e-9);
    EXPECT_LT((got[k].gyro_rad_s - truth[k].gyro_rad_s).norm(), 1e-9);
    EXPECT_EQ(got[k].stamp.host, truth[k].stamp.host);
  }
  EXPECT_NE(source->summary().find("samples 50"), std::string::npos) << source->summary();
}

}  // namespace
}  // namespace livod::daemon
