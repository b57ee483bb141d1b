#pragma once
// Scenarios: a world, a trajectory of the body (IMU) frame, and the sensors mounted on the body
// with their clock and link faults. The named scenarios cover the estimator's test matrix; a
// YAML file can describe custom ones (see docs/simulator.md).

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tools/sim/camera_sim.hpp"
#include "tools/sim/imu_model.hpp"
#include "tools/sim/sensor_clock.hpp"
#include "tools/sim/sensor_sim.hpp"
#include "tools/sim/trajectory.hpp"

namespace livod::sim {

enum class WorldKind { kRoom, kCorridor, kCorridorSideRooms, kStreet };

struct LidarMount {
  std::string model;  // as `livod decode --model` spells it: OS1-64, OS1-128, VLP-16, AVIA, MID-360
  std::string name;   // sensor name in the generated config (unique)
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  ClockFaults clock;
  LinkFaults link;
  RangeModel range;
  bool imu = true;  // emit the LiDAR-internal IMU (when the model has one)
  ImuNoiseParams imu_noise;
  double scan_rate_hz = 10.0;  // 10 or 20 (SimLidarOptions::scan_rate_hz)
};

struct CameraMount {
  std::string name = "cam0";
  CameraSimParams params;
  Eigen::Isometry3d T_body_cam = Eigen::Isometry3d::Identity();
  double time_offset_s = 0.0;  // stamps = true mid-exposure + this (a calibration error to find)
};

// The wire format of the CAN IMU: SBG Ellipse (sensor-protocols.md 7.1 example B; a device
// microsecond counter) or Bosch MM7.10 (example A; no timestamp, a 4-bit message counter).
enum class CanImuFormat { kSbg, kBoschMm7 };

// An IMU on the CAN bus.
struct CanImuMount {
  std::string name = "can_imu";
  CanImuFormat format = CanImuFormat::kSbg;
  Eigen::Isometry3d T_body_imu = Eigen::Isometry3d::Identity();
  ImuNoiseParams noise;
  ClockFaults clock;  // of its microsecond counter (SBG; the MM7 has no clock)
  LinkFaults link;    // bus + driver latency to the host receive stamp
};

// The wire protocol of the serial IMU: an Xsens MTi's MTData2 (float32 PacketCounter,
// SampleTimeFine, Acceleration, RateOfTurn, StatusWord) or a VectorNav VN-100's binary output
// (Common group: TimeStartup, AngularRate, Accel; IMU group: SensSat).
enum class SerialImuProtocol { kXsensMtData2, kVectorNavBinary };

// An IMU on a serial line, as the host reads it: in chunks that end anywhere, so messages are
// torn across reads; optionally with corrupted messages and line noise.
struct SerialImuMount {
  std::string name = "serial_imu";
  SerialImuProtocol protocol = SerialImuProtocol::kXsensMtData2;
  Eigen::Isometry3d T_body_imu = Eigen::Isometry3d::Identity();
  ImuNoiseParams noise = ImuNoiseParams{.rate_hz = 400.0};
  ClockFaults clock;                 // of SampleTimeFine (10 kHz ticks) / TimeStartup (ns)
  int baud_rate = 921600;            // 10 bits per byte on the wire
  double read_latency_s = 1e-3;      // mean of the exponential host read latency (adapter + OS)
  std::size_t max_read_bytes = 64;   // reads return 1..max bytes (uniform)
  double corrupt_probability = 0.0;  // per message: one byte flipped (checksum error)
  double noise_probability = 0.0;    // per message: 1..8 random bytes on the line before it
};

struct Scenario {
  std::string name;
  std::string description;
  WorldKind world = WorldKind::kRoom;
  double street_length_m = 420.0;
  // What moves and what scatters in the world: pedestrians and cars (moving_objects.hpp), foliage
  // (worlds.hpp). The named street and room scenarios have some; see docs/simulator.md.
  SceneContent scene;
  TrajectorySpec trajectory;
  double duration_s = 30.0;
  std::vector<LidarMount> lidars;
  std::vector<CameraMount> cameras;
  std::optional<CanImuMount> can_imu;
  std::optional<SerialImuMount> serial_imu;
  // Which IMU defines the body frame: "<lidar name>" (its internal IMU), the CAN IMU's or the
  // serial IMU's name.
  std::string body_imu;
  double groundtruth_rate_hz = 200.0;
};

// The range model of a LiDAR model as its datasheet describes it (noise, detection limit, beam
// divergence, range walk; sources in scenario.cpp and docs/simulator.md). The named scenarios
// mount their LiDARs with it; unknown models get RangeModel's plain defaults.
RangeModel datasheet_range_model(const std::string& model);

// `range` without the realism effects (divergence, detection limit, range walk, noise growth):
// Gaussian noise of sigma_m, dropouts and the range limits only.
RangeModel plain_range_model(const RangeModel& range);

// Names of the built-in scenarios with a one-line description each.
std::vector<std::pair<std::string, std::string>> list_scenarios();

// A built-in scenario by name; throws livod::Error listing the known names if unknown.
Scenario make_scenario(const std::string& name);

// A custom scenario from YAML (documented in docs/simulator.md); throws livod::Error listing every
// problem found.
Scenario load_scenario_yaml(const std::filesystem::path& path);

}  // namespace livod::sim
