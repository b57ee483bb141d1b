#pragma once
// Xsens MTi (MTi 1/10/100/600-series) binary output, the Xbus MTData2 message of the Xsens "MT
// Low-Level Communication Protocol" (sensor-protocols.md 7.2):
//
//   0xFA preamble | BID (0xFF) | MID (0x36 = MTData2) | LEN u8 [0xFF: then LEN u16 big-endian]
//   | data | checksum
//
// The checksum byte makes the sum of every byte from BID through the checksum 0 modulo 256. The
// data of MTData2 is a sequence of items {XDI u16 BE, size u8, value (big-endian)}. This decoder
// reads:
//   0x1020 PacketCounter   u16        sample counter (gaps = lost messages)
//   0x1060 SampleTimeFine  u32        the sensor clock, 10 kHz ticks (wraps after ~4.97 days;
//                                     unwrapped here)
//   0x4020 Acceleration    3 reals    m/s^2, sensor frame       (0x4040 AccelerationHR)
//   0x8020 RateOfTurn      3 reals    rad/s, sensor frame       (0x8040 RateOfTurnHR)
//   0xE020 StatusWord      u32        bits 8-13: accelerometer x/y/z, gyroscope x/y/z clipping
// Reals come in the precision the low two XDI bits select: 0 float32, 1 fixed 12.20 (i32 / 2^20),
// 2 fixed 16.32 (u32 fraction then i16 integer), 3 float64. The coordinate-system bits (2-3) select
// the local frame of orientation and velocity outputs; Acceleration and RateOfTurn are in the
// sensor frame either way. Other items (orientation, magnetometer, ...) and other messages
// (acknowledgements, errors) are skipped.
//
// One MTData2 with both acceleration and rate of turn is one sample, stamped with SampleTimeFine
// (which must be configured; a sample without it is dropped as `incomplete`) and the receive time
// of the read that completed the message. Messages may be cut anywhere between reads; garbage
// and corrupted messages (bad checksum, impossible length) are skipped and counted, and the
// decoder resynchronises on the next preamble, also inside the rejected bytes.

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "drivers/imu/imu_decoder.hpp"

namespace livod::imu {

class XsensMtData2Decoder final : public StreamImuDecoder {
 public:
  // Largest message accepted (extended length up to 2048 data bytes, as the MT manuals state).
  static constexpr std::size_t kMaxDataBytes = 2048;

  XsensMtData2Decoder() = default;

  void on_bytes(std::span<const std::byte> bytes, std::int64_t rx_time_ns,
                const ImuSink& sink) override;
  [[nodiscard]] const ImuDecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] bool has_sensor_clock() const override { return true; }
  [[nodiscard]] std::string model_name() const override { return "Xsens MTi (MTData2)"; }

  // The newest MTData2's packet counter and status word, when present.
  [[nodiscard]] std::optional<std::uint16_t> last_packet_counter() const;
  [[nodiscard]] std::uint32_t last_status_word() const { return status_word_; }
  // Xbus messages other than MTData2 seen (acknowledgements, errors, configuration replies).
  [[nodiscard]] std::uint64_t other_messages() const { return other_messages_; }

 private:
  // Parses whole messages at the front of buf_; returns after consuming what it can.
  void drain(std::int64_t rx_time_ns, const ImuSink& sink);
  void handle_mtdata2(std::span<const std::uint8_t> data, std::int64_t rx_time_ns,
                      const ImuSink& sink);

  ImuDecoderCounters counters_;
  // Preamble..checksum of the largest message: 1 + 1 + 1 + 3 + kMaxDataBytes + 1.
  std::array<std::uint8_t, kMaxDataBytes + 7> buf_{};
  std::size_t size_ = 0;
  bool have_counter_ = false;
  std::uint16_t last_counter_ = 0;
  bool have_time_ = false;
  std::uint32_t last_ticks_ = 0;
  std::int64_t wrap_ticks_ = 0;
  std::uint32_t status_word_ = 0;
  std::uint64_t other_messages_ = 0;
};

// ---- encoding (simulator, tests) ----------------------------------------------------------------

// One complete Xbus message: preamble, BID 0xFF, `mid`, length (extended when > 254), data,
// checksum.
std::vector<std::uint8_t> encode_xbus_message(std::uint8_t mid, std::span<const std::uint8_t> data);

enum class XsensPrecision : std::uint8_t { float32 = 0, fp1220 = 1, fp1632 = 2, float64 = 3 };

struct XsensSample {
  std::uint16_t packet_counter = 0;
  std::uint32_t sample_time_fine = 0;  // 10 kHz ticks
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  std::uint32_t status_word = 0;
  XsensPrecision precision = XsensPrecision::float32;
};

// One MTData2 message carrying PacketCounter, SampleTimeFine, Acceleration, RateOfTurn and
// StatusWord in that order.
std::vector<std::uint8_t> encode_mtdata2_sample(const XsensSample& sample);

}  // namespace livod::imu
