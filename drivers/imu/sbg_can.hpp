#pragma once
// SBG Systems Ellipse/HPINS IMU output over CAN (open spec: SBG sbgECom doc/canProtocol.md and
// can/sbgCan.dbc, summarised in sensor-protocols.md 7.1 example B). Default identifiers:
//   0x120 IMU_INFO : time_stamp u32 us since power-on, imu_status u16, temperature i16 x0.01 degC
//   0x121 IMU_ACCEL: accel x, y, z  i16 x0.01 m/s^2
//   0x122 IMU_GYRO : gyro  x, y, z  i16 x0.001 rad/s
// All little-endian (Intel) signed signals. One sample = INFO, ACCEL, GYRO in that order; the
// sample carries the INFO frame's device time. The 32-bit microsecond counter wraps every
// ~71.6 min and is unwrapped here.

#include <array>
#include <cstdint>
#include <optional>

#include "core/measurement.hpp"

namespace livod::imu {

struct SbgCanIds {
  std::uint32_t info = 0x120;
  std::uint32_t accel = 0x121;
  std::uint32_t gyro = 0x122;
};

// One CAN frame's essentials (what the decoder needs; no dependency on the log format).
struct CanPayload {
  std::uint32_t id = 0;
  std::uint8_t len = 0;
  std::array<std::uint8_t, 8> data{};
  std::int64_t rx_time_ns = 0;  // host receive time of the frame (CLOCK_MONOTONIC or log time)
};

struct SbgSample {
  ImuSample imu;  // stamp.sensor = unwrapped device time; stamp.host = INFO rx time
  std::uint16_t status = 0;
  double temperature_c = 0.0;
};

struct SbgDecoderCounters {
  std::uint64_t frames = 0;
  std::uint64_t samples = 0;
  std::uint64_t malformed = 0;   // wrong length
  std::uint64_t incomplete = 0;  // a sample whose ACCEL or GYRO frame never came
  std::uint64_t counter_wraps = 0;
};

class SbgCanDecoder {
 public:
  explicit SbgCanDecoder(SbgCanIds ids = {}) : ids_(ids) {}

  // Feeds one frame; returns a complete sample when the GYRO frame closes one. Frames with other
  // identifiers are ignored (not counted as errors: the bus carries other traffic).
  std::optional<SbgSample> on_frame(const CanPayload& frame);

  [[nodiscard]] const SbgDecoderCounters& counters() const { return counters_; }

 private:
  SbgCanIds ids_;
  SbgDecoderCounters counters_;
  bool have_info_ = false;
  bool have_accel_ = false;
  SbgSample pending_;
  std::uint32_t last_raw_us_ = 0;
  std::int64_t wrap_offset_us_ = 0;
  bool seen_counter_ = false;
};

// Encodes one sample as its three frames (used by the simulator and by tests). Values outside
// the i16 range saturate, as the device's would.
std::array<CanPayload, 3> encode_sbg_sample(std::uint32_t device_time_us,
                                            const Eigen::Vector3d& accel_m_s2,
                                            const Eigen::Vector3d& gyro_rad_s, double temperature_c,
                                            const SbgCanIds& ids = {});

}  // namespace livod::imu
