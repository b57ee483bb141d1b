#pragma once
// Stateful Velodyne driver behind drivers::LidarDecoder: data packets -> scans (frame cut by
// azimuth or time), position packets -> GPS time anchor and (HDL-32E) IMU samples, counters.
//
// Time (docs/drivers/velodyne.md): Stamp::sensor of a scan is the time of its first point on
// the sensor timeline, i.e. the top-of-hour microseconds with the hour chosen by the §4.6 rule
// against the first packet's receive time, then unwrapped across rollovers and re-anchored
// (whole hours, current scan included) when a valid $GPRMC disagrees. Stamp::host is the
// receive time of the packet that carried the scan's first point. Stamp::mapped = host is a
// placeholder (as in the Ouster driver): the decoder has no clock model, the clock domain
// downstream replaces it. t_offset_ns of each point is from the scan's first point.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/measurement.hpp"
#include "drivers/azimuth_window.hpp"
#include "drivers/lidar_decoder.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/data_packet.hpp"
#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/position_packet.hpp"
#include "drivers/velodyne/top_of_hour.hpp"

namespace livod::drivers::velodyne {

enum class ScanCut : std::uint8_t {
  kAzimuthDecrease,  // new scan when a block azimuth is below the previous one (VeloView)
  kAzimuthAngle,     // new scan when the block azimuth passes `cut_angle_deg`
  kTimePeriod,       // new scan when the block time enters a new multiple of `cut_period_ns`
};

struct VelodyneOptions {
  Model model = Model::kVlp16;
  // The sensor's FOV setting (web interface "FOV start/end"). Without it the decoder learns the
  // window from the packets that straddle its edge (an azimuth jump inside a packet), and tells
  // the skipped sector from lost packets from then on; configured, it does so from the start.
  std::optional<AzimuthWindow> fov;
  std::optional<std::filesystem::path> calibration_file;  // default: the model's nominal table
  DecodeSettings decode;
  ScanCut cut = ScanCut::kAzimuthDecrease;
  double cut_angle_deg = 0.0;
  std::int64_t cut_period_ns = 100'000'000;
};

// Velodyne-specific counters beyond DecoderCounters.
struct VelodyneCounters {
  std::uint64_t factory_byte_mismatches = 0;  // data packets whose byte 1205 names another model
  std::uint64_t zero_ranges = 0;              // returns with distance 0 (dropped)
  std::uint64_t duplicate_returns = 0;        // dual-return repeats of a single echo (dropped)
  std::uint64_t out_of_range = 0;             // returns outside [min_range, max_range] (dropped)
  std::uint64_t late_packets = 0;             // reordered or repeated data packets (dropped)
  std::uint64_t position_packets = 0;         // position packets decoded
  std::uint64_t gps_fixes = 0;                // position packets with a valid $GPRMC
  std::uint64_t hour_rollovers = 0;           // top-of-hour counter rollovers followed
  std::uint64_t time_rebases = 0;             // hour re-anchors from GPS
  std::uint64_t bad_length = 0;               // payloads neither 1206 nor 512 bytes
  std::uint64_t bad_content = 0;              // 1206/512-byte payloads with invalid fields
  std::uint64_t fov_boundary_packets = 0;     // packets with an azimuth jump (reduced FOV)
  std::uint64_t undated_blocks = 0;  // blocks after a jump that no rotation rate could date
};

class VelodyneDecoder final : public LidarDecoder {
 public:
  // Throws livod::Error / FormatError if the calibration cannot be used for the model.
  VelodyneDecoder(const VelodyneOptions& options, const Calibration& calibration);
  // Loads options.calibration_file, or the model's nominal table when none is given.
  explicit VelodyneDecoder(const VelodyneOptions& options);

  void on_packet(const PacketView& packet, const DecoderSinks& sinks) override;
  void flush(const DecoderSinks& sinks) override;
  [[nodiscard]] const DecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] std::vector<std::uint16_t> default_ports() const override;
  [[nodiscard]] std::string model_name() const override;

  [[nodiscard]] const VelodyneCounters& velodyne_counters() const { return velodyne_; }
  // The last position packet's PPS status and GPS fix, if any arrived.
  [[nodiscard]] std::optional<PpsStatus> last_pps() const { return last_pps_; }
  [[nodiscard]] const std::optional<RmcFix>& last_fix() const { return last_fix_; }

 private:
  void on_data_packet(const PacketView& packet, const DecoderSinks& sinks);
  void on_position_packet(const PacketView& packet, const DecoderSinks& sinks);
  [[nodiscard]] bool should_cut(std::uint16_t azimuth, std::int64_t block_time_ns) const;
  void emit_scan(const DecoderSinks& sinks, bool complete);
  void append_block(std::span<const DecodedReturn> returns, std::int64_t packet_ns);

  VelodyneOptions options_;
  DataPacketDecoder decoder_;
  DecoderCounters counters_;
  VelodyneCounters velodyne_;
  TopOfHourClock clock_;
  std::array<DecodedReturn, DataPacketDecoder::kMaxReturns> returns_{};

  LidarScan scan_;
  bool scan_started_at_cut_ = false;  // false for the first scan of a stream (partial)
  bool scan_has_gap_ = false;
  std::uint32_t next_sequence_ = 0;

  bool have_previous_block_ = false;
  std::uint16_t previous_block_azimuth_ = 0;
  std::int64_t previous_block_time_ns_ = 0;

  // The configured FOV window, or else the one learned from the last boundary packet.
  [[nodiscard]] int skipped_centideg(std::uint16_t from, std::uint16_t to) const {
    if (options_.fov) return options_.fov->skipped_on_path_centideg(from, to);
    return learned_fov_ ? learned_fov_->skipped_on_path_centideg(from, to) : 0;
  }

  bool have_previous_packet_ = false;
  std::uint16_t previous_last_azimuth_ = 0;  // last block of the previous packet
  std::int32_t previous_last_block_ns_ = 0;  // its time from the previous packet's stamp
  std::uint32_t previous_packet_toh_us_ = 0;
  double azimuth_rate_ = 0.0;  // 0.01 degree per ns, last measured
  // Long-baseline rotation rate: azimuth advance and time summed over the recent jump-free
  // packets with exponential forgetting; dates the blocks after a FOV jump.
  std::optional<AzimuthWindow> learned_fov_;
  double rate_advance_sum_ = 0.0;
  double rate_time_sum_ns_ = 0.0;

  std::optional<PpsStatus> last_pps_;
  std::optional<RmcFix> last_fix_;
};

}  // namespace livod::drivers::velodyne
