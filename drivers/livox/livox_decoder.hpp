#pragma once
// Scan assembly for Livox LiDARs (SDK1 and SDK2 models) behind drivers::LidarDecoder. Livox
// scanning is non-repetitive, so a scan is a time window: points are cut into scans of
// `scan_period_ns` aligned to multiples of the period on the sensor clock (like livox_ros_driver's
// 10 Hz frames). SDK2 sequence gaps come from udp_cnt; SDK1 has no counter, so a gap is a packet
// timestamp further than 1.5 packet spans after the previous one, and the count is bounded by
// what the receive times allow: a sensor-time advance more than kMaxUnexplainedAdvanceNs beyond
// the receive-time advance, a step back of more than kMaxReorderNs, or a change of timestamp type
// is a clock jump (PTP/GPS sync gained, reset), counted in clock_jumps, never as lost packets.

#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include "drivers/lidar_decoder.hpp"
#include "drivers/livox/packets.hpp"

namespace livod::livox {

enum class Protocol { kSdk1, kSdk2 };

struct LivoxModel {
  std::string name;  // AVIA, HORIZON, TELE-15, MID-40, MID-70, MID-360, HAP
  Protocol protocol = Protocol::kSdk1;
  std::uint32_t point_interval_ns = 4167;  // SDK1 only
  std::uint8_t lines = 6;
  std::uint16_t data_port = 56001;  // host ports livod asks for / the vendor defaults
  std::uint16_t imu_port = 56001;
};

// The model's decoder facts from the Livox family tables (livox_family.cpp; names matched as
// drivers::normalise_model_name does); nullopt for an unknown model name.
std::optional<LivoxModel> livox_model(const std::string& name);

struct LivoxDecoderOptions {
  std::int64_t scan_period_ns = 100'000'000;
  bool drop_invalid_points = true;  // no-return points are not emitted
  bool keep_first_return_only = false;
};

class LivoxDecoder final : public drivers::LidarDecoder {
 public:
  LivoxDecoder(LivoxModel model, LivoxDecoderOptions options);

  void on_packet(const drivers::PacketView& packet, const drivers::DecoderSinks& sinks) override;
  void flush(const drivers::DecoderSinks& sinks) override;
  [[nodiscard]] const drivers::DecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] std::vector<std::uint16_t> default_ports() const override;
  [[nodiscard]] std::string model_name() const override { return model_.name; }

  [[nodiscard]] std::uint64_t decode_error_count(DecodeError e) const {
    return error_counts_[static_cast<std::size_t>(e)];
  }

 private:
  void emit(const drivers::DecoderSinks& sinks);

  LivoxModel model_;
  LivoxDecoderOptions options_;
  drivers::DecoderCounters counters_;
  std::array<std::uint64_t, kDecodeErrorKinds> error_counts_{};
  LivoxPacket packet_;
  LidarScan scan_;
  bool scan_open_ = false;
  std::int64_t scan_index_ = 0;  // floor(sensor time / period) of the open scan
  // The newest window any point fell into: points of older windows are late (dropped), unless
  // they are so much older that the sensor clock was reset (then the timeline restarts).
  std::int64_t newest_index_ = std::numeric_limits<std::int64_t>::min();
  static constexpr std::int64_t kClockResetWindows = 20;
  std::uint32_t next_sequence_ = 0;
  std::optional<std::uint16_t> last_udp_cnt_;
  std::optional<std::int64_t> last_packet_end_ns_;
  std::int64_t last_packet_host_ns_ = 0;
  std::uint8_t last_time_type_ = 0;
  // How far the sensor timestamps may run ahead of the receive stamps between two packets before
  // the difference is a clock jump: generous for bursty delivery and coarse capture stamps.
  static constexpr std::int64_t kMaxUnexplainedAdvanceNs = 1'000'000'000;
  // Packets delivered this much older than the newest one are a clock step back, not reordering.
  static constexpr std::int64_t kMaxReorderNs = 100'000'000;
  std::int32_t last_span_ns_ = 0;
};

}  // namespace livod::livox
