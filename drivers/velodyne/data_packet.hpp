#pragma once
// Velodyne data packet decoder (1206-byte payload, §4.1/§4.3/§4.4 of
// shared/docs/sensor-protocols.md): a pure function of the payload and tables fixed at
// construction. No allocation, every length and field checked.
//
// Conventions (docs/drivers/velodyne.md):
// * Points are in livod's LiDAR frame, x forward (azimuth 0), y left, z up:
//     x = xy cos(a) + h sin(a),  y = -xy sin(a) + h cos(a),  z = d sin(w) + v cos(w),
//     xy = d cos(w) - v sin(w),  a = azimuth - rot_correction,  d = raw * unit + dist_correction
//   (h, v: horizontal/vertical beam offsets; zero for the nominal tables). This is the ROS
//   velodyne / VDEC model; VeloView's y-forward frame is (x_vv, y_vv) = (-y, x).
// * Zero ranges ("no return") are dropped and counted, as are ranges outside (min, max].
// * Per-point azimuth is interpolated from the block azimuth with the packet's mean rotation
//   rate and the firing time of the point (§4.3).
// * Per-point time follows the firing time: the timing table, plus, after an azimuth jump inside
//   the packet (the boundary packet of a reduced field of view), the time the head needed to
//   turn through the skipped sector (block_delay_ns). Without a usable rotation rate such blocks
//   cannot be dated: they are dropped and counted (undated_blocks).
// * Dual return: the odd block of a pair repeats the even block's firings; an odd-block return
//   with the same raw distance as its partner is a duplicate and is dropped. return_index 0 is
//   the stronger return of the pair (ties: the nearer one), 1 the other; single-return
//   packets have return_index 0.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/firing_timing.hpp"
#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::drivers::velodyne {

enum class AzimuthInterpolation : std::uint8_t {
  // a = block azimuth + rate * (firing time - block time), rate = the packet's mean rotation
  // rate (first to last block), full floating-point resolution. The default.
  kPacketRate,
  // VeloView 3.x (vtkVelodyneHDLReader): rate from the median of adjacent block azimuth
  // differences, the correction rounded to the sensor's 0.01 degree. Only for VLP-16 and
  // HDL-32E; exists to check this decoder against VeloView's published reference values.
  kVeloView,
};

struct DecodeSettings {
  double min_range_m = 0.0;  // returns with range <= min are dropped (zero ranges always are)
  double max_range_m = std::numeric_limits<double>::infinity();  // and those > max
  AzimuthInterpolation azimuth = AzimuthInterpolation::kPacketRate;
  double vls128_channel_us = kVls128ChannelUsOldFirmware;
};

struct DecodedReturn {
  float x = 0, y = 0, z = 0;      // metres, LiDAR frame
  float distance_m = 0;           // corrected range
  float azimuth_rad = 0;          // beam azimuth as the sensor counts it (clockwise from +x
                                  // seen from above), [0, 2 pi)
  std::int32_t t_offset_ns = 0;   // firing time minus the packet timestamp
  std::uint16_t laser = 0;        // laser id (calibration index)
  std::uint16_t ring = 0;         // elevation rank, 0 = lowest beam
  std::uint8_t intensity = 0;     // reflectivity as sent
  std::uint8_t return_index = 0;  // see the header comment
  std::uint8_t block = 0;         // block index in the packet
};

enum class DataDecodeStatus : std::uint8_t {
  kOk,
  kBadLength,
  kBadBlockFlag,
  kBadAzimuth,
  kBadTimestamp
};

struct DataPacketResult {
  DataDecodeStatus status = DataDecodeStatus::kBadLength;
  std::uint32_t toh_us = 0;
  std::uint8_t return_mode_byte = 0;
  std::uint8_t factory_byte = 0;
  bool dual = false;
  int blocks_used = 0;
  std::array<std::uint16_t, wire::kBlocksPerPacket> block_azimuth{};  // 0.01 degree, 0..36000
  // Index in the output of the first return of each block; [blocks_used] is the total count.
  std::array<std::uint16_t, wire::kBlocksPerPacket + 1> block_begin{};
  std::size_t count = 0;
  // Mean azimuth rate inside the packet (0.01 degree per ns), when the packet spans more than
  // one firing sequence; the decoder feeds it back as the fallback for packets that do not.
  std::optional<double> azimuth_rate;
  std::uint16_t zero_ranges = 0;
  std::uint16_t duplicates = 0;
  std::uint16_t out_of_range = 0;
  std::uint8_t undated_blocks = 0;  // blocks after a jump with no rotation rate to date them
  // Firing delay of each block beyond the timing table (ns). Non-zero only after an azimuth
  // discontinuity inside the packet: a sensor with a reduced field of view (FOV setting) pauses
  // outside its window and fills the remaining blocks of the boundary packet when the window
  // reopens, so those blocks fire (skipped sector / rotation rate) later than the table says.
  std::array<std::int32_t, wire::kBlocksPerPacket> block_delay_ns{};
  std::uint8_t azimuth_jumps = 0;       // discontinuities found in this packet
  std::uint16_t jump_from_azimuth = 0;  // the last one: block azimuths before and after it
  std::uint16_t jump_to_azimuth = 0;
  // Time of the last used block (its firing sequence's reference instant, delay included) from
  // the packet timestamp: the next packet continues from there.
  std::int32_t last_block_time_ns = 0;
  std::uint16_t last_block_azimuth = 0;
};

// block_delay_ns of a block after a jump that no rotation rate can date.
inline constexpr std::int32_t kUndatableDelay = std::numeric_limits<std::int32_t>::max();

class DataPacketDecoder {
 public:
  static constexpr std::size_t kMaxReturns = wire::kReturnsPerPacket;

  // Throws livod::Error if the calibration does not fit the model.
  DataPacketDecoder(Model model, const Calibration& calibration, DecodeSettings settings);

  // Decodes one payload into `out` (capacity >= kMaxReturns). `fallback_rate` (0.01 degree per
  // ns) is used when the packet holds a single firing sequence (VLS-128 dual return).
  // `dating_rate` (same unit; 0 = none) dates the blocks after an azimuth jump: a rate averaged
  // over many packets is far more precise than one packet's (whose azimuths are quantised to
  // 0.01 degree); without it the packet's median sequence rate is used.
  [[nodiscard]] DataPacketResult decode(std::span<const std::byte> payload, double fallback_rate,
                                        std::span<DecodedReturn> out,
                                        double dating_rate = 0.0) const;

  [[nodiscard]] Model model() const { return model_; }
  [[nodiscard]] const FiringTiming& timing() const { return timing_; }
  [[nodiscard]] const DecodeSettings& settings() const { return settings_; }

 private:
  struct LaserTable {
    double cos_vert, sin_vert;
    double cos_rot, sin_rot;
    double rot_rad;
    double rot_deg;
    double dist_correction_m;
    double vert_offset_m, horiz_offset_m;
    std::uint16_t ring;
  };

  [[nodiscard]] int laser_of(std::uint16_t flag, int channel) const;
  [[nodiscard]] double veloview_azimuth_diff(const DataPacketResult& r) const;
  // Median azimuth rate over consecutive firing sequences (0.01 degree per ns); nullopt when the
  // packet has fewer than three sequence transitions.
  [[nodiscard]] std::optional<double> median_sequence_rate(const DataPacketResult& r) const;

  Model model_;
  DecodeSettings settings_;
  FiringTiming timing_;
  double distance_unit_m_;
  std::vector<LaserTable> lasers_;  // sized once at construction
};

}  // namespace livod::drivers::velodyne
