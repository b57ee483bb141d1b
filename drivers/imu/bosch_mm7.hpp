#pragma once
// Bosch MM7-series automotive 6-axis IMU (MM7.10) on CAN (sensor-protocols.md 7.1 example A; the
// signal table of Bosch's own open-source receiver, bosch-engineering/off_highway_sensor_drivers
// off_highway_mm7p10). 500 kbit/s, typically 100 Hz, three classic 8-byte frames per sample, all
// signals Intel (little-endian) unsigned:
//
//   id     frame  bits 0-15          16-19     20-23       24-31        32-47   48-51    52-55
//   0x174  TX1    yaw rate (z)        -         yaw STAT    temperature  AY      MSG_CNT  AY STAT
//   0x178  TX2    roll rate (x)       -         roll STAT   -            AX      MSG_CNT  AX STAT
//   0x17C  TX3    pitch rate (y)      HW index  pitch STAT  -            AZ      MSG_CNT  AZ STAT
//   (bits 56-63: a CRC whose algorithm is not public; it is not checked)
//
//   rates: raw * 0.005 - 163.84 deg/s; accelerations: raw * 0.000127465 - 4.1768 g;
//   temperature: raw - 50 degC (0xFF: CRC error or below -50 degC, 0xC9: above 150 degC).
//   STAT nibbles: bit 0 IMU not available, bit 1 signal failure, bit 2 initialisation running.
//
// The three frames of one sample carry the same 4-bit MSG_CNT; TX1 starts a sample, TX3 completes
// it. The sensor's roll rate is reported with the opposite sign of the right-hand rule about x
// (Bosch's driver negates it too): the decoder negates it, so samples are right-handed.
//
// The MM7 has no timestamp: stamp.sensor = stamp.host = the receive time of TX1
// (has_sensor_clock() is false; map it in receive_time mode with the bus latency). A sample with
// any STAT bit set is dropped and counted `invalid`; MSG_CNT steps of more than one between
// consecutive samples count `sequence_gaps`.

#include <array>
#include <cstdint>

#include "drivers/imu/imu_decoder.hpp"

namespace livod::imu {

struct BoschMm7Ids {
  std::uint32_t tx1 = 0x174;  // yaw rate + AY
  std::uint32_t tx2 = 0x178;  // roll rate + AX
  std::uint32_t tx3 = 0x17C;  // pitch rate + AZ
};

class BoschMm7Decoder final : public CanImuDecoder {
 public:
  explicit BoschMm7Decoder(BoschMm7Ids ids = {}) : ids_(ids) {}

  void on_frame(const CanRecord& frame, const ImuSink& sink) override;
  [[nodiscard]] const ImuDecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] std::vector<std::uint32_t> frame_ids() const override {
    return {ids_.tx1, ids_.tx2, ids_.tx3};
  }
  [[nodiscard]] bool has_sensor_clock() const override { return false; }
  [[nodiscard]] std::string model_name() const override { return "Bosch MM7"; }

  // From the newest TX1 frame; NaN when the sensor flags the temperature invalid.
  [[nodiscard]] double last_temperature_c() const { return temperature_c_; }
  [[nodiscard]] std::uint8_t last_hw_index() const { return hw_index_; }

 private:
  BoschMm7Ids ids_;
  ImuDecoderCounters counters_;
  ImuSample pending_;
  int stage_ = 0;  // 0: waiting for TX1, 1: have TX1, 2: have TX2
  std::uint8_t counter_ = 0;
  std::uint8_t status_ = 0;
  bool have_last_counter_ = false;
  std::uint8_t last_counter_ = 0;
  double temperature_c_ = 0.0;
  std::uint8_t hw_index_ = 0;
};

// Per-channel STAT nibbles for the encoder (tests, simulator): yaw, ay, roll, ax, pitch, az.
struct BoschMm7Status {
  std::array<std::uint8_t, 6> stat{};
};

// Encodes one sample (specific force in m/s^2 and rate in rad/s, right-handed IMU frame) as its
// three frames with message counter `counter` (low 4 bits). Values quantise to the wire LSB
// (0.005 deg/s, 0.000127465 g) and saturate at the wire range. The CRC byte is left 0.
std::array<CanRecord, 3> encode_bosch_mm7_sample(
    std::uint8_t counter, const Eigen::Vector3d& accel_m_s2, const Eigen::Vector3d& gyro_rad_s,
    double temperature_c, const BoschMm7Status& status = {}, const BoschMm7Ids& ids = {});

}  // namespace livod::imu
