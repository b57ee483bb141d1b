#pragma once
// VectorNav VN-100 / VN-200 / VN-300 binary output messages (the "Binary Output" registers 75-77 of
// the VectorNav user manuals / ICDs), as a serial stream:
//
//   0xFA sync | groups u8 | one group field u16 (little-endian) per selected group, in group order
//   | payload: every selected field of every selected group, group by group, field bits in
//     ascending order, each little-endian (float32 / float64 / integers) | CRC u16 big-endian
//
// The CRC is CRC-16-CCITT (polynomial 0x1021, initial value 0, no reflection: CRC-16/XMODEM) over
// the bytes from the groups byte through the payload; run over those bytes and the CRC itself it
// gives 0. Group bits 0-6 select groups 1-7 (Common, Time, IMU, GNSS, Attitude, INS, GNSS2); a
// packet's length follows from the fixed size of every field (kVectorNavFieldBytes), so a field
// whose size is not known (a reserved bit, the extension bit 7 of the groups byte or bit 15 of a
// group field that newer firmware uses for groups 8+ and fields 16+) makes the packet impossible to
// frame: it is counted `malformed` and the decoder resynchronises on the next 0xFA.
//
// The decoder reads, from any group that carries them:
//   TimeStartup  u64 ns since the sensor started (Common bit 0, Time bit 0): the sensor clock.
//                Required: a sample without it is dropped as `incomplete`.
//   AngularRate  3 x f32 rad/s, compensated (Common bit 5, IMU bit 10)
//   Accel        3 x f32 m/s^2, compensated (Common bit 8, IMU bit 9); specific force
//   Imu          6 x f32: UncompAccel m/s^2, UncompGyro rad/s (Common bit 9)
//   UncompAccel, UncompGyro  3 x f32 each (IMU bits 2, 3)
//   SensSat      u16 saturation flags (IMU bit 11): bits 3-5 accelerometer x/y/z, 6-8 gyro x/y/z
//   SyncInCnt    u32 (Common bit 13, Time bit 7), TimeSyncIn u64 ns (Common bit 2, Time bit 4):
//                kept for the caller (last_sync_in()), not used as the clock (TimeSyncIn restarts
//                at every SyncIn edge).
// When a packet carries both, the compensated outputs (the sensor's calibration, its reference
// frame rotation and its onboard bias estimate applied) win over the uncompensated ones. The
// sensor has no packet counter: lost packets are counted (`sequence_gaps`) from TimeStartup steps
// larger than 1.5 times the smallest step seen (the output period). A backwards step is a restart.
//
// ASCII messages on the same port ($VN...*XX) never contain 0xFA and are skipped as
// `skipped_bytes`. Packets may be cut anywhere between reads.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "drivers/imu/imu_decoder.hpp"

namespace livod::imu {

// Byte size of each field bit of groups 1-7 (0: reserved or unknown size). Facts of the VectorNav
// ICD tables (VN-100/200/300 firmware 1.x/2.x): Common, Time, IMU, GNSS, Attitude, INS, GNSS2.
inline constexpr std::array<std::array<std::uint8_t, 16>, 7> kVectorNavFieldBytes{{
    {8, 8, 8, 12, 16, 12, 24, 12, 12, 24, 20, 28, 2, 4, 8, 0},     // Common
    {8, 8, 8, 2, 8, 8, 8, 4, 4, 1, 0, 0, 0, 0, 0, 0},              // Time
    {2, 12, 12, 12, 4, 4, 16, 12, 12, 12, 12, 2, 40, 0, 0, 0},     // IMU
    {8, 8, 2, 1, 1, 24, 24, 12, 12, 12, 4, 4, 2, 28, 0, 0},        // GNSS
    {2, 12, 16, 36, 12, 12, 12, 12, 12, 12, 28, 24, 12, 0, 0, 0},  // Attitude
    {2, 24, 24, 12, 12, 12, 12, 12, 12, 4, 4, 68, 64, 0, 0, 0},    // INS
    {8, 8, 2, 1, 1, 24, 24, 12, 12, 12, 4, 4, 2, 28, 0, 0},        // GNSS2
}};

// Payload bytes of a packet selecting every known field of every group.
[[nodiscard]] constexpr std::size_t vectornav_max_payload_bytes() {
  std::size_t n = 0;
  for (const auto& group : kVectorNavFieldBytes) {
    for (const auto bytes : group) n += bytes;
  }
  return n;
}

// CRC-16-CCITT as VectorNav uses it (poly 0x1021, init 0, MSB first).
[[nodiscard]] std::uint16_t vectornav_crc16(std::span<const std::uint8_t> bytes);

class VectorNavBinaryDecoder final : public StreamImuDecoder {
 public:
  // Sync, groups byte, 7 group fields, every field of groups 1-7, CRC.
  static constexpr std::size_t kMaxPacketBytes =
      1 + 1 + 2 * kVectorNavFieldBytes.size() + vectornav_max_payload_bytes() + 2;

  VectorNavBinaryDecoder() = default;

  void on_bytes(std::span<const std::byte> bytes, std::int64_t rx_time_ns,
                const ImuSink& sink) override;
  [[nodiscard]] const ImuDecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] bool has_sensor_clock() const override { return true; }
  [[nodiscard]] std::string model_name() const override { return "VectorNav (binary output)"; }

  struct SyncIn {
    std::uint32_t count = 0;          // SyncInCnt
    std::uint64_t time_since_ns = 0;  // TimeSyncIn (0 when the packet did not carry it)
  };
  // The newest SyncIn counter, when a packet carried one.
  [[nodiscard]] std::optional<SyncIn> last_sync_in() const { return sync_in_; }
  // The newest SensSat flags (0 when never received).
  [[nodiscard]] std::uint16_t last_saturation() const { return sens_sat_; }
  // Valid packets without accelerations or angular rates (attitude-only, GNSS, ...).
  [[nodiscard]] std::uint64_t other_packets() const { return other_packets_; }

 private:
  void drain(std::int64_t rx_time_ns, const ImuSink& sink);
  // Header at buf_[pos]: packet size, 0 while more bytes are needed, nullopt when not a packet.
  [[nodiscard]] std::optional<std::size_t> packet_size(std::size_t pos) const;
  void handle_packet(std::size_t pos, std::int64_t rx_time_ns, const ImuSink& sink);

  ImuDecoderCounters counters_;
  std::array<std::uint8_t, kMaxPacketBytes> buf_{};
  std::size_t size_ = 0;
  bool have_time_ = false;
  std::uint64_t last_time_ns_ = 0;
  std::uint64_t period_ns_ = 0;  // smallest TimeStartup step seen (0: none yet)
  std::optional<SyncIn> sync_in_;
  std::uint16_t sens_sat_ = 0;
  std::uint64_t other_packets_ = 0;
};

// ---- encoding (simulator, tests) ----------------------------------------------------------------

// One complete packet: sync, `groups`, the group fields (one per set bit of `groups`, in order),
// `payload`, CRC. No check that the payload matches the fields.
std::vector<std::uint8_t> encode_vectornav_packet(std::uint8_t groups,
                                                  std::span<const std::uint16_t> group_fields,
                                                  std::span<const std::uint8_t> payload);

struct VectorNavSample {
  std::uint64_t time_startup_ns = 0;
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  std::uint16_t sens_sat = 0;
  // false: Common group TimeStartup, AngularRate, Accel + IMU group SensSat (what the simulator
  // sends); true: Common group TimeStartup and Imu (uncompensated accel + gyro) only.
  bool uncompensated = false;
};

std::vector<std::uint8_t> encode_vectornav_sample(const VectorNavSample& sample);

}  // namespace livod::imu
