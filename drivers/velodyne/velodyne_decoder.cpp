#include "drivers/velodyne/velodyne_decoder.hpp"

#include "core/numeric.hpp"

#include <algorithm>
#include <cmath>

#include "drivers/velodyne/velodyne_family.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr int kHalfTurn = 18000;  // 0.01 degree
constexpr std::int64_t kHalfHourUs = 1'800'000'000;
// Consecutive packets further apart than this are not used to estimate a rotation rate.
constexpr std::int64_t kMaxRateBaselineNs = 10'000'000;
// Scans are reserved for 1/8 s of single-return points: a 10 Hz scan with margin, so that
// steady state does not allocate; slower or dual-return sensors grow it once.
constexpr double kReservedScanSeconds = 0.125;
// Forgetting factor of the long-baseline rotation rate, per packet (about 30 packets' memory).
constexpr double kRateMemory = 0.97;
// Below half a turn per second the azimuth says nothing reliable about missing packets.
constexpr double kMinGapRateCentidegPerNs = 0.5 * 36000.0 * 1e-9;

Calibration calibration_for(const VelodyneOptions& options) {
  return options.calibration_file ? load_calibration(*options.calibration_file)
                                  : default_calibration(options.model);
}

bool imu_words_present(const PositionPacket& p) {
  for (const auto& m : p.motion) {
    if (m.gyro_deg_s != 0.0 || m.accel_x_g != 0.0 || m.accel_y_g != 0.0) return true;
  }
  return false;
}

}  // namespace

VelodyneDecoder::VelodyneDecoder(const VelodyneOptions& options, const Calibration& calibration)
    : options_(options), decoder_(options.model, calibration, options.decode) {
  scan_.reserve(
      static_cast<std::size_t>(traits(options.model).points_per_second * kReservedScanSeconds));
}

VelodyneDecoder::VelodyneDecoder(const VelodyneOptions& options)
    : VelodyneDecoder(options, calibration_for(options)) {}

std::vector<std::uint16_t> VelodyneDecoder::default_ports() const {
  // The family table's vendor defaults (velodyne_family.cpp), the same for every model.
  const UdpPorts& ports = velodyne_family().models.front().ports;
  return {ports.lidar, ports.position};
}

std::string VelodyneDecoder::model_name() const {
  return std::string(traits(options_.model).name);
}

void VelodyneDecoder::on_packet(const PacketView& packet, const DecoderSinks& sinks) {
  ++counters_.packets;
  if (packet.payload.size() == wire::kDataPacketSize) {
    on_data_packet(packet, sinks);
  } else if (packet.payload.size() == wire::kPositionPacketSize) {
    on_position_packet(packet, sinks);
  } else {
    ++counters_.decode_errors;
    ++velodyne_.bad_length;
  }
}

bool VelodyneDecoder::should_cut(std::uint16_t azimuth, std::int64_t block_time_ns) const {
  if (!have_previous_block_) return false;
  switch (options_.cut) {
    case ScanCut::kAzimuthDecrease:
      return azimuth < previous_block_azimuth_;
    case ScanCut::kAzimuthAngle: {
      const int advance = (36000 + azimuth - previous_block_azimuth_) % 36000;
      if (advance == 0) return false;
      if (advance >= kHalfTurn) return true;  // lost half a turn or more: the scan is broken
      const auto cut = static_cast<int>(std::lround(options_.cut_angle_deg * 100.0)) % 36000;
      const int to_cut = ((cut - previous_block_azimuth_) % 36000 + 36000) % 36000;
      return to_cut > 0 && to_cut <= advance;
    }
    case ScanCut::kTimePeriod:
      return floor_div(block_time_ns, options_.cut_period_ns) !=
             floor_div(previous_block_time_ns_, options_.cut_period_ns);
  }
  return false;
}

void VelodyneDecoder::emit_scan(const DecoderSinks& sinks, bool complete) {
  if (scan_.empty()) return;
  scan_.sequence = next_sequence_++;
  ++counters_.scans;
  counters_.points += scan_.size();
  if (!complete || !scan_started_at_cut_ || scan_has_gap_) ++counters_.incomplete_scans;
  if (sinks.on_scan) sinks.on_scan(scan_);
  scan_.clear();
  scan_has_gap_ = false;
}

void VelodyneDecoder::on_data_packet(const PacketView& packet, const DecoderSinks& sinks) {
  const auto payload = packet.payload;
  // Rate fallback for packets that hold a single firing sequence: the azimuth advance from the
  // previous packet's last block over the time between them.
  double fallback_rate = azimuth_rate_;
  const std::uint32_t toh_us = wire::u32le(payload, wire::kTimestampOffset);
  const std::uint16_t first_azimuth = wire::u16le(payload, 2);
  if (have_previous_packet_ && first_azimuth <= wire::kAzimuthUnitsPerTurn) {
    const std::int64_t dt_ns =
        (static_cast<std::int64_t>(toh_us) - previous_packet_toh_us_) * 1000 -
        previous_last_block_ns_;
    const int advance = (36000 + first_azimuth - previous_last_azimuth_) % 36000 -
                        skipped_centideg(previous_last_azimuth_, first_azimuth);
    if (dt_ns > 0 && dt_ns <= kMaxRateBaselineNs && advance > 0 && advance < kHalfTurn) {
      fallback_rate = advance / static_cast<double>(dt_ns);
    }
  }

  const double dating_rate = rate_time_sum_ns_ > 0.0 ? rate_advance_sum_ / rate_time_sum_ns_ : 0.0;
  const DataPacketResult r = decoder_.decode(payload, fallback_rate, returns_, dating_rate);
  if (r.status != DataDecodeStatus::kOk) {
    ++counters_.decode_errors;
    ++velodyne_.bad_content;
    return;
  }
  ++counters_.lidar_packets;
  if (r.factory_byte != traits(options_.model).factory_byte) ++velodyne_.factory_byte_mismatches;
  velodyne_.zero_ranges += r.zero_ranges;
  velodyne_.duplicate_returns += r.duplicates;
  velodyne_.out_of_range += r.out_of_range;
  velodyne_.undated_blocks += r.undated_blocks;
  const double rate = r.azimuth_rate.value_or(fallback_rate);
  if (r.azimuth_jumps > 0) {
    ++velodyne_.fov_boundary_packets;
    if (!options_.fov && rate > 0.0) {
      // The window ends one firing sequence's rotation after the last block before the jump
      // and starts at the first block after it.
      const double step = rate * static_cast<double>(decoder_.timing().packet_period_ns(r.dual)) /
                          static_cast<double>(r.blocks_used);
      learned_fov_ = AzimuthWindow{r.jump_to_azimuth / 100.0,
                                   std::fmod((r.jump_from_azimuth + step) / 100.0, 360.0)};
    }
  }

  // Continuity with the previous packet, from its last block to this packet's first block. The
  // timestamp tells late or repeated packets (which would cut a scan and put points out of time
  // order: they are dropped) from losses; the azimuth counts the lost packets, one packet's worth
  // of rotation each. The FOV's skipped sector is no loss (inside a boundary packet the decode
  // already dated it). Packets holding one firing sequence (no in-packet rate) or losses of half
  // a turn or more are counted by time.
  const FiringTiming& timing = decoder_.timing();
  if (have_previous_packet_) {
    std::int64_t dt_us = static_cast<std::int64_t>(r.toh_us) - previous_packet_toh_us_;
    if (dt_us < -kHalfHourUs) dt_us += 2 * kHalfHourUs;  // the counter rolled over the hour
    if (dt_us <= 0) {
      ++velodyne_.late_packets;
      return;
    }
    const std::int64_t period_ns = timing.packet_period_ns(r.dual);
    // Nominal time from a packet's last firing sequence to the next packet's first.
    const std::int64_t step_ns = period_ns - (timing.block_reference_ns(r.dual, r.blocks_used - 1) -
                                              timing.block_reference_ns(r.dual, 0));
    const int skipped = skipped_centideg(previous_last_azimuth_, r.block_azimuth[0]);
    const int advance = (36000 + r.block_azimuth[0] - previous_last_azimuth_) % 36000 - skipped;
    std::int64_t missing = 0;
    if (advance < kHalfTurn && r.azimuth_rate && *r.azimuth_rate > kMinGapRateCentidegPerNs) {
      const double expected = *r.azimuth_rate * static_cast<double>(step_ns);
      missing =
          std::llround((advance - expected) / (*r.azimuth_rate * static_cast<double>(period_ns)));
    } else {
      double gap_ns = static_cast<double>(dt_us * 1000 + timing.block_reference_ns(r.dual, 0) -
                                          previous_last_block_ns_ - step_ns);
      if (skipped > 0 && rate > kMinGapRateCentidegPerNs) gap_ns -= skipped / rate;
      missing = std::llround(gap_ns / static_cast<double>(period_ns));
    }
    if (missing > 0) {
      counters_.sequence_gaps += static_cast<std::uint64_t>(missing);
      scan_has_gap_ = true;
    }
  }
  if (r.azimuth_jumps == 0 && r.azimuth_rate) {
    const int last = r.blocks_used - 1;
    const std::int32_t span_ns =
        timing.block_reference_ns(r.dual, last) - timing.block_reference_ns(r.dual, 0);
    const int advance_in_packet =
        (36000 + r.block_azimuth[static_cast<std::size_t>(last)] - r.block_azimuth[0]) % 36000;
    rate_advance_sum_ = kRateMemory * rate_advance_sum_ + advance_in_packet;
    rate_time_sum_ns_ = kRateMemory * rate_time_sum_ns_ + span_ns;
  }
  have_previous_packet_ = true;
  previous_last_azimuth_ = r.last_block_azimuth;
  previous_last_block_ns_ = r.last_block_time_ns;
  previous_packet_toh_us_ = r.toh_us;
  azimuth_rate_ = rate;

  const std::uint64_t rollovers_before = clock_.hour_rollovers();
  const std::int64_t packet_ns = clock_.to_sensor_ns(r.toh_us, packet.host_time_ns);
  velodyne_.hour_rollovers += clock_.hour_rollovers() - rollovers_before;

  for (int b = 0; b < r.blocks_used; ++b) {
    const std::int32_t delay = r.block_delay_ns[static_cast<std::size_t>(b)];
    if (delay == kUndatableDelay) continue;
    const std::uint16_t azimuth = r.block_azimuth[static_cast<std::size_t>(b)];
    const std::int64_t block_ns = packet_ns + timing.block_reference_ns(r.dual, b) + delay;
    if (should_cut(azimuth, block_ns)) {
      emit_scan(sinks, true);
      scan_started_at_cut_ = true;
    }
    have_previous_block_ = true;
    previous_block_azimuth_ = azimuth;
    previous_block_time_ns_ = block_ns;

    const std::size_t begin = r.block_begin[static_cast<std::size_t>(b)];
    const std::size_t end = r.block_begin[static_cast<std::size_t>(b) + 1];
    if (begin == end) continue;
    if (scan_.empty()) {
      scan_.start.sensor = SensorTime(packet_ns + returns_[begin].t_offset_ns);
      // The packet leaves when its last firing sequence is done: its receive time, back-dated by
      // the firings from this point on, is the point's (a clock fed by scans alone would
      // otherwise carry up to a packet of accumulation, 1.3 ms on a VLP-16, varying with where
      // the scan was cut; docs/clocks.md). The last block's delay (a field-of-view pause) delays
      // the packet too.
      const std::int64_t packet_end_ns = r.last_block_time_ns + timing.packet_period_ns(r.dual) -
                                         timing.block_reference_ns(r.dual, r.blocks_used - 1);
      const std::int64_t accumulation =
          std::max<std::int64_t>(0, packet_end_ns - returns_[begin].t_offset_ns);
      scan_.start.host = HostTime(packet.host_time_ns - accumulation);
      scan_.start.mapped = MappedTime(scan_.start.host.ns);  // placeholder, see header
    }
    append_block(std::span(returns_).subspan(begin, end - begin), packet_ns);
  }
}

void VelodyneDecoder::append_block(std::span<const DecodedReturn> returns, std::int64_t packet_ns) {
  // One resize per block instead of eight capacity checks per point: this loop is most of the
  // driver's time after the packet decode itself.
  const std::size_t base = scan_.size();
  const std::size_t n = base + returns.size();
  scan_.x.resize(n);
  scan_.y.resize(n);
  scan_.z.resize(n);
  scan_.intensity.resize(n);
  scan_.ring.resize(n);
  scan_.return_index.resize(n);
  scan_.t_offset_ns.resize(n);
  scan_.valid.resize(n, 1);
  const std::int64_t offset_base = packet_ns - scan_.start.sensor.ns;
  for (std::size_t k = 0; k < returns.size(); ++k) {
    const DecodedReturn& p = returns[k];
    const std::size_t i = base + k;
    scan_.x[i] = p.x;
    scan_.y[i] = p.y;
    scan_.z[i] = p.z;
    scan_.intensity[i] = static_cast<float>(p.intensity);
    scan_.ring[i] = p.ring;
    scan_.return_index[i] = p.return_index;
    scan_.t_offset_ns[i] = static_cast<std::int32_t>(offset_base + p.t_offset_ns);
  }
}

void VelodyneDecoder::on_position_packet(const PacketView& packet, const DecoderSinks& sinks) {
  const PositionDecodeResult r = decode_position_packet(packet.payload);
  if (r.status != PositionDecodeStatus::kOk) {
    ++counters_.decode_errors;
    ++velodyne_.bad_content;
    return;
  }
  ++velodyne_.position_packets;
  const PositionPacket& p = r.packet;
  last_pps_ = p.pps;

  const std::uint64_t rollovers_before = clock_.hour_rollovers();
  std::int64_t sensor_ns = clock_.to_sensor_ns(p.toh_us, packet.host_time_ns);
  velodyne_.hour_rollovers += clock_.hour_rollovers() - rollovers_before;

  if (p.rmc && p.rmc->valid) {
    ++velodyne_.gps_fixes;
    last_fix_ = p.rmc;
    // The GPS date fixes the hour; the receive-time anchor can be off by whole hours (a host
    // clock that is not UTC). Move the timeline, the scan being built included, so that its
    // point offsets stay consistent.
    const std::int64_t gps_ns = resolve_top_of_hour(p.toh_us, p.rmc->utc_ns);
    const auto hours = static_cast<std::int64_t>(
        std::llround(static_cast<double>(gps_ns - sensor_ns) / static_cast<double>(kHourNs)));
    if (hours != 0) {
      clock_.shift_hours(hours);
      if (!scan_.empty()) scan_.start.sensor += Nanoseconds(hours * kHourNs);
      previous_block_time_ns_ += hours * kHourNs;
      sensor_ns += hours * kHourNs;
      ++velodyne_.time_rebases;
    }
  }

  if (options_.model == Model::kHdl32e && imu_words_present(p)) {
    ++counters_.imu_packets;
    const ImuVectors v = hdl32e_imu_in_lidar_frame(p);
    ImuSample sample;
    sample.stamp.sensor = SensorTime(sensor_ns);
    sample.stamp.host = HostTime(packet.host_time_ns);
    sample.stamp.mapped = MappedTime(packet.host_time_ns);  // placeholder, see header
    sample.gyro_rad_s = v.gyro_rad_s;
    sample.accel_m_s2 = v.accel_m_s2;
    if (sinks.on_imu) sinks.on_imu(sample);
  } else {
    ++counters_.aux_packets;
  }
}

void VelodyneDecoder::flush(const DecoderSinks& sinks) {
  emit_scan(sinks, false);
}

}  // namespace livod::drivers::velodyne
