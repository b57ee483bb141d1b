#pragma once
// SBG Systems Ellipse/HPINS IMU output over CAN (open spec: SBG sbgECom doc/canProtocol.md and
// can/sbgCan.dbc, summarised in sensor-protocols.md 7.1 example B). Default identifiers:
//   0x120 IMU_INFO : time_stamp u32 us since power-on, imu_status u16, temperature i16 x0.01 degC
//   0x121 IMU_ACCEL: accel x, y, z  i16 x0.01 m/s^2
//   0x122 IMU_GYRO : gyro  x, y, z  i16 x0.001 rad/s
// All little-endian (Intel) signed signals. One sample = INFO, ACCEL, GYRO in that order; the
// sample carries the INFO frame's device time and receive time. The 32-bit microsecond counter
// wraps every ~71.6 min and is unwrapped here.

#include <array>
#include <cstdint>

#include "drivers/imu/imu_decoder.hpp"

namespace livod::imu {

struct SbgCanIds {
  std::uint32_t info = 0x120;
  std::uint32_t accel = 0x121;
  std::uint32_t gyro = 0x122;
};

class SbgCanDecoder final : public CanImuDecoder {
 public:
  explicit SbgCanDecoder(SbgCanIds ids = {}) : ids_(ids) {}

  void on_frame(const CanRecord& frame, const ImuSink& sink) override;
  [[nodiscard]] const ImuDecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] std::vector<std::uint32_t> frame_ids() const override {
    return {ids_.info, ids_.accel, ids_.gyro};
  }
  [[nodiscard]] bool has_sensor_clock() const override { return true; }
  [[nodiscard]] std::string model_name() const override { return "SBG"; }

  // Of the newest INFO frame.
  [[nodiscard]] std::uint16_t last_status() const { return status_; }
  [[nodiscard]] double last_temperature_c() const { return temperature_c_; }

 private:
  SbgCanIds ids_;
  ImuDecoderCounters counters_;
  bool have_info_ = false;
  bool have_accel_ = false;
  ImuSample pending_;
  std::uint16_t status_ = 0;
  double temperature_c_ = 0.0;
  std::uint32_t last_raw_us_ = 0;
  std::int64_t wrap_offset_us_ = 0;
  bool seen_counter_ = false;
};

// Encodes one sample as its three frames (used by the simulator and by tests). Values outside
// the i16 range saturate, as the device's would.
std::array<CanRecord, 3> encode_sbg_sample(std::uint32_t device_time_us,
                                           const Eigen::Vector3d& accel_m_s2,
                                           const Eigen::Vector3d& gyro_rad_s, double temperature_c,
                                           const SbgCanIds& ids = {});

}  // namespace livod::imu
