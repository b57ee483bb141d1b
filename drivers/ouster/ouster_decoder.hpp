#pragma once
// Scan assembly for Ouster sensors: lidar, IMU and zone packets in (any mix on one port), one
// LidarScan per frame and SI ImuSamples out.
//
// Frames: a frame is the set of packets with one frame_id. It is emitted as soon as the column
// that comes last in time within the column window has arrived (for a window that wraps through
// column 0, e.g. [370, 85], that is column W-1), or when a packet of another frame arrives, or on
// flush(). Completeness is judged against the column window of the metadata: a frame missing any
// window column is incomplete and is published or dropped according to the options.
//
// Points: one per valid column x row x return with a non-zero range (or every pixel, flagged, when
// keep_invalid_points is set), in arrival order: column by column, rows 0..H-1 within a column,
// first return then second. Coordinates are metres in the Ouster sensor frame (x forward). Each
// point's time is the timestamp of the column it was measured in; the scan's start is the first
// column of the frame, so t_offset_ns = ts[column] - ts[first column]. Points are NOT destaggered:
// a point list needs no image order. (If you build a destaggered image, pixel (u, v) holds
// measurement column (v - pixel_shift_by_row[u]) mod W and must take that column's time.)
//
// Stamps: `sensor` is the Ouster timestamp (ns; its epoch depends on timestamp_mode), `host` the
// receive time of the packet that carried the frame's first column (or the IMU sample). The
// decoder has no clock model, so it sets `mapped` = `host` as a placeholder; the clock domain
// downstream replaces it.
//
// Sensor re-initialisation: a lidar packet whose init_id differs from the current one (non-LEGACY
// only) means the sensor restarted. The partial frame is discarded (counted as incomplete),
// frame tracking restarts and ouster_counters().init_id_changes counts it. The metadata is still
// used: beam intrinsics do not change on re-init, and a changed profile or mode shows up as size
// or measurement-id errors. metadata_init_id_mismatch() tells the caller to refetch it.
//
// Steady state allocates nothing: the scan buffers are reserved for a full frame up front.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/lidar_decoder.hpp"
#include "drivers/ouster/imu_packet.hpp"
#include "drivers/ouster/lidar_packet.hpp"
#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/packet_format.hpp"
#include "drivers/ouster/xyz_lut.hpp"

namespace livod::drivers::ouster {

enum class IncompleteScanPolicy : std::uint8_t { kPublish, kDrop };

struct OusterDecoderOptions {
  IncompleteScanPolicy incomplete_scans = IncompleteScanPolicy::kPublish;
  // Emit every pixel (range 0 and invalid columns included, valid = 0) instead of returns only.
  bool keep_invalid_points = false;
  CrcPolicy crc = CrcPolicy::kAuto;
  // Reject non-LEGACY packets whose serial number differs from the metadata's (another sensor
  // sending to the same port; ouster-sdk's same_ports captures).
  bool check_serial_number = true;
};

// Ouster-specific counters, beyond the generic DecoderCounters.
struct OusterCounters {
  std::uint64_t wrong_size = 0;           // length matches no packet of this configuration
  std::uint64_t wrong_packet_type = 0;    // unknown packet_type (or not lidar/IMU/zone)
  std::uint64_t crc_failures = 0;         // CRC-64 footer mismatches
  std::uint64_t bad_measurement_ids = 0;  // out of range or not consecutive within a packet
  std::uint64_t serial_mismatches = 0;    // packets from another sensor (prod_sn differs)
  std::uint64_t init_id_changes = 0;      // the sensor re-initialised while streaming
  std::uint64_t frame_id_gaps = 0;        // frames skipped entirely (frame_id jumped)
  std::uint64_t missing_columns = 0;      // column-window columns due but never received
  std::uint64_t late_packets = 0;         // packets of a frame already emitted, or out of order
  std::uint64_t dropped_incomplete_scans = 0;  // incomplete scans not published (kDrop)
  std::uint64_t invalid_columns = 0;           // column-window columns with status bit 0 clear
  std::uint64_t zone_packets = 0;              // zone-monitoring packets (validated, not decoded)
  std::uint64_t imu_samples = 0;               // IMU samples emitted
  std::uint64_t invalid_imu_samples = 0;       // samples with status bit 0 clear (not emitted)
  std::uint64_t thermal_shutdown_packets = 0;  // lidar packets with thermal_shutdown != 0
  std::uint64_t shot_limiting_packets = 0;     // lidar packets with shot_limiting != 0
  std::uint64_t timestamp_jumps = 0;           // columns > 2.1 s from their frame start (skipped)
};

// The sensor's status flags from the latest lidar packet header (non-LEGACY profiles).
struct OusterSensorStatus {
  std::uint8_t alert_flags = 0;
  std::uint8_t countdown_thermal_shutdown = 0;
  std::uint8_t countdown_shot_limiting = 0;
  std::uint8_t thermal_shutdown = 0;  // 1: thermal shutdown imminent
  std::uint8_t shot_limiting = 0;     // 1: imminent; 2..9: laser power reduced 0-10 % .. 70-80 %
  std::uint32_t init_id = 0;
  std::uint32_t frame_id = 0;
};

class OusterDecoder final : public LidarDecoder {
 public:
  explicit OusterDecoder(SensorMetadata metadata, OusterDecoderOptions options = {});

  void on_packet(const PacketView& packet, const DecoderSinks& sinks) override;
  void flush(const DecoderSinks& sinks) override;
  [[nodiscard]] const DecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] std::vector<std::uint16_t> default_ports() const override;
  [[nodiscard]] std::string model_name() const override;

  [[nodiscard]] const OusterCounters& ouster_counters() const { return ouster_counters_; }
  [[nodiscard]] const OusterSensorStatus& sensor_status() const { return status_; }
  [[nodiscard]] const SensorMetadata& metadata() const { return metadata_; }
  [[nodiscard]] const PacketFormat& packet_format() const { return format_; }
  // True once a lidar packet carried an init_id different from the metadata's
  // initialization_id: the sensor was re-initialised since the metadata was read.
  [[nodiscard]] bool metadata_init_id_mismatch() const { return metadata_init_id_mismatch_; }

 private:
  struct Frame {
    bool open = false;
    std::uint32_t frame_id = 0;
    std::uint64_t start_ts_ns = 0;  // timestamp of the first column that produced the scan start
    bool have_start = false;
    std::uint32_t next_measurement_id = 0;  // first column expected in the next packet
    std::uint32_t window_columns = 0;       // window columns received (any status)
    std::uint32_t window_packets = 0;       // packets received with at least one window column
    std::uint32_t valid_columns = 0;        // columns that produced points
    std::uint64_t valid_points = 0;
    std::int32_t last_offset_ns = 0;  // offset of the latest valid column
    // The previous frame of this run was seen, so columns missing before this frame's first
    // packet were lost (for the first frame of a capture or after a re-init they were never due).
    bool continues = false;
    bool have_window_packet = false;
    std::uint32_t first_window_packet = 0;  // packet index (measurement_id / columns per packet)
    std::uint32_t last_window_packet = 0;
  };

  void on_lidar(const PacketView& packet, const DecoderSinks& sinks);
  void on_imu(const PacketView& packet, const DecoderSinks& sinks);
  void count_error(PacketError error);
  void open_frame(std::uint32_t frame_id);
  // at_end: the capture ended (flush), so the columns after the last packet were never due.
  void close_frame(const DecoderSinks& sinks, bool at_end = false);
  void discard_frame();
  void add_columns(const LidarPacket& packet, std::int64_t host_time_ns);
  [[nodiscard]] bool in_window(std::uint32_t column) const;
  // Window columns / window packets measured before column `column` / packet `packet` of a frame.
  [[nodiscard]] std::uint32_t window_columns_before(std::uint32_t column) const;
  [[nodiscard]] std::uint32_t window_packets_before(std::uint32_t packet) const;

  SensorMetadata metadata_;
  OusterDecoderOptions options_;
  PacketFormat format_;
  XyzLut lut_;

  std::uint32_t window_size_ = 0;          // columns in the column window
  std::uint32_t last_column_in_time_ = 0;  // window column measured last in a frame
  std::uint32_t window_packet_slots_ = 0;  // packets per frame that carry window columns

  Frame frame_;
  std::optional<std::uint32_t> last_closed_frame_id_;
  std::optional<std::uint32_t> current_init_id_;
  bool metadata_init_id_mismatch_ = false;

  LidarScan scan_;
  std::uint32_t scan_sequence_ = 0;
  ImuPacket imu_packet_;
  ImuSample imu_sample_;

  DecoderCounters counters_;
  OusterCounters ouster_counters_;
  OusterSensorStatus status_;
};

}  // namespace livod::drivers::ouster
