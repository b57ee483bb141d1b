#pragma once
// Stateful Hesai driver behind drivers::LidarDecoder: point cloud packets -> scans, counters.
//
// Geometry: geometry.hpp (the angle correction file's angles, no interpolation within a block,
// livod's frame x forward / y left / z up; nebula's clouds keep Hesai's frame, where (x, y) is
// (-y, x) here). Distances are raw x the packet's dis unit.
//
// Time: Stamp::sensor is UTC from the packet tail (date + microseconds; PTP- or GPS-synchronised
// units give true UTC, free-running ones their own clock). Each point's time is its firing time
// (firing_timing.hpp). Stamp::host is the receive time of the packet that carried the scan's
// first firing; Stamp::mapped = host is a placeholder for the clock domain downstream.
//
// Scans (ScanCut::kAzimuth): every point belongs to the turn in which its own horizontal angle
// (block azimuth + the channel's correction) passes the cut angle, so a scan holds exactly the
// points with angles in [cut, cut + 360) of one turn, as nebula cuts. ScanCut::kTimePeriod cuts
// on multiples of the period (block start times). The first scan of a stream, the last one
// (flush) and scans with lost packets are incomplete.
//
// Dual return: blocks come in pairs at one azimuth; a second-block return equal to the first
// block's (the returns coincide) is a duplicate and dropped. return_index 0 is the stronger of
// the two (ties: the nearer), 1 the other.
//
// Loss: the UDP sequence number counts lost packets when the packets carry it; otherwise the
// packet timestamps do (bounded by the receive times: a larger jump is a clock jump). With the
// sensor's start/end angle configured (fov), the packets of the skipped sector are not loss.
// Packets older than the newest one (sequence or time) are late: dropped and counted.

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/measurement.hpp"
#include "drivers/azimuth_window.hpp"
#include "drivers/hesai/calibration.hpp"
#include "drivers/hesai/firing_timing.hpp"
#include "drivers/hesai/geometry.hpp"
#include "drivers/hesai/model.hpp"
#include "drivers/hesai/packet.hpp"
#include "drivers/lidar_decoder.hpp"

namespace livod::drivers::hesai {

inline constexpr std::uint16_t kDataPort = 2368;
inline constexpr std::uint16_t kGpsPort = 10110;

enum class ScanCut : std::uint8_t { kAzimuth, kTimePeriod };

struct HesaiOptions {
  Model model = Model::kPandarXT32;
  std::optional<std::filesystem::path> calibration_file;  // required unless corrections given
  double min_range_m = 0.0;  // returns with range <= min are dropped (zero ranges always are)
  double max_range_m = std::numeric_limits<double>::infinity();  // and those > max
  ScanCut cut = ScanCut::kAzimuth;
  double cut_angle_deg = 0.0;
  std::int64_t cut_period_ns = 100'000'000;
  std::optional<AzimuthWindow> fov;  // the sensor's start/end angle setting
};

struct HesaiCounters {
  std::array<std::uint64_t, kPacketErrorKinds> packet_errors{};  // by PacketError
  std::uint64_t gps_packets = 0;               // 512-byte GPS packets (counted, not decoded)
  std::uint64_t zero_ranges = 0;               // returns with distance 0 (no return)
  std::uint64_t duplicate_returns = 0;         // dual-return repeats of one echo (dropped)
  std::uint64_t out_of_range = 0;              // returns outside (min_range, max_range]
  std::uint64_t late_packets = 0;              // reordered or repeated packets (dropped)
  std::uint64_t high_temperature_packets = 0;  // the sensor announced a thermal shutdown
  std::uint64_t fov_boundary_packets = 0;      // packets with an azimuth jump (start/end angle)
  std::uint16_t motor_rpm = 0;                 // of the latest packet
  std::uint8_t return_mode = 0;                // of the latest packet
};

class HesaiDecoder final : public LidarDecoder {
 public:
  // Throws livod::Error when the corrections do not fit the model.
  HesaiDecoder(const HesaiOptions& options, AngleCorrections corrections);
  // Loads options.calibration_file; throws livod::Error if it is missing or unusable.
  explicit HesaiDecoder(const HesaiOptions& options);

  void on_packet(const PacketView& packet, const DecoderSinks& sinks) override;
  void flush(const DecoderSinks& sinks) override;
  [[nodiscard]] const DecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] std::vector<std::uint16_t> default_ports() const override {
    return {kDataPort, kGpsPort};
  }
  [[nodiscard]] std::string model_name() const override;

  [[nodiscard]] const HesaiCounters& hesai_counters() const { return hesai_; }

 private:
  struct Channel {
    double azimuth_centideg;  // the azimuth correction
    std::uint16_t ring;
  };
  struct Assembly {
    LidarScan scan;
    bool started_at_cut = false;
    bool has_gap = false;
  };

  // False when the packet is late (dropped).
  bool check_continuity(const PacketView& packet);
  void block_delays(bool dual, std::array<std::int32_t, kMaxBlocks>& delay);
  // rx_minus_sensor: the packet's receive time less the sensor time its last firing ended
  // (a point's receive time, back-dated to it, is rx_minus_sensor + its sensor time).
  void add_block(int block, bool dual, std::int32_t delay, std::int64_t packet_ns,
                 std::int64_t rx_minus_sensor, const DecoderSinks& sinks);
  void emit(Assembly& a, const DecoderSinks& sinks, bool complete);
  void advance_turn(const DecoderSinks& sinks);
  void append(Assembly& a, std::int64_t block_start_ns, std::int64_t rx_minus_sensor,
              std::int64_t t_ns, float x, float y, float z, float intensity, std::uint16_t ring,
              std::uint8_t return_index);

  HesaiOptions options_;
  const ModelTraits& traits_;
  AngleCorrections corrections_;
  FiringTiming timing_;
  BeamGeometry geometry_;
  std::vector<Channel> channels_;
  double min_correction_centideg_ = 0.0;
  int cut_centideg_ = 0;

  HesaiPacket packet_;
  DecoderCounters counters_;
  HesaiCounters hesai_;
  std::uint32_t next_sequence_ = 0;

  // Continuity.
  bool have_previous_ = false;
  std::optional<std::uint32_t> previous_udp_sequence_;
  std::int64_t previous_packet_ns_ = 0;
  std::int64_t previous_host_ns_ = 0;
  std::uint16_t previous_last_azimuth_ = 0;

  // Assembly: the open turn and the next one (azimuth cut), or one scan (time cut).
  std::array<Assembly, 2> assemblies_;
  int current_ = 0;
  bool have_phase_ = false;
  std::int64_t block_turn_ = 0;  // turns of the block azimuth past the cut angle
  int last_phase_ = 0;           // block azimuth minus the cut angle, 0.01 degree
  std::int64_t turn_ = 0;        // the turn of assemblies_[current_]
  std::int64_t period_index_ = 0;
  bool have_period_ = false;

  static constexpr std::int64_t kMaxReorderNs = 100'000'000;
  static constexpr std::int64_t kMaxUnexplainedAdvanceNs = 1'000'000'000;
  // A scan spanning longer than this (a stopped motor) is emitted as incomplete.
  static constexpr std::int64_t kMaxScanSpanNs = 1'000'000'000;
};

}  // namespace livod::drivers::hesai
