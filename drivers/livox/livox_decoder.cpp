#include "drivers/livox/livox_decoder.hpp"

#include <algorithm>

#include "core/numeric.hpp"

namespace livod::livox {

LivoxDecoder::LivoxDecoder(LivoxModel model, LivoxDecoderOptions options)
    : model_(std::move(model)), options_(options) {
  // Capacity for a full scan at the fastest model (240 kpts/s x 3 returns) so steady state never
  // reallocates.
  scan_.reserve(static_cast<std::size_t>(240'000.0 * 3.0 *
                                         static_cast<double>(options_.scan_period_ns) * 1e-9) +
                1024);
}

std::vector<std::uint16_t> LivoxDecoder::default_ports() const {
  if (model_.data_port == model_.imu_port) return {model_.data_port};
  return {model_.data_port, model_.imu_port};
}

void LivoxDecoder::on_packet(const drivers::PacketView& packet,
                             const drivers::DecoderSinks& sinks) {
  ++counters_.packets;
  const DecodeError err =
      model_.protocol == Protocol::kSdk1
          ? decode_sdk1(packet.payload, model_.point_interval_ns, model_.lines, packet_)
          : decode_sdk2(packet.payload, model_.lines, packet_);
  if (err != DecodeError::kNone) {
    ++counters_.decode_errors;
    ++error_counts_[static_cast<std::size_t>(err)];
    return;
  }
  if (packet_.kind == LivoxPacket::Kind::kImu) {
    ++counters_.imu_packets;
    if (sinks.on_imu) {
      ImuSample s;
      s.stamp.sensor = SensorTime(packet_.timestamp_ns);
      s.stamp.host = HostTime(packet.host_time_ns);
      s.stamp.mapped = MappedTime(packet.host_time_ns);  // until a clock domain maps it
      s.gyro_rad_s = packet_.gyro_rad_s;
      s.accel_m_s2 = packet_.accel_m_s2;
      sinks.on_imu(s);
    }
    return;
  }
  ++counters_.lidar_packets;

  // Clock jumps: the timestamp type changed, the time went back further than any reordering
  // explains, or it went ahead further than the receive times allow (lost packets take their
  // time on the link too). The timeline restarts; nothing is counted lost across the jump.
  bool jumped = false;
  if (last_packet_end_ns_) {
    const std::int64_t host_advance =
        std::max<std::int64_t>(0, packet.host_time_ns - last_packet_host_ns_);
    const std::int64_t advance = packet_.timestamp_ns - *last_packet_end_ns_;
    jumped = packet_.time_type != last_time_type_ || advance < -kMaxReorderNs ||
             advance > host_advance + kMaxUnexplainedAdvanceNs;
  }
  if (jumped) {
    ++counters_.clock_jumps;
    last_packet_end_ns_.reset();
  }

  // Sequence gaps. A packet older than the newest one seen (reordered or delayed on the link) is
  // not a gap, and the newest one stays the reference; it was counted missing when its successor
  // came, so it takes one back: sequence_gaps counts the packets that never arrived.
  const bool older = last_packet_end_ns_ && packet_.timestamp_ns <= *last_packet_end_ns_;
  if (older && counters_.sequence_gaps > 0) --counters_.sequence_gaps;
  if (model_.protocol == Protocol::kSdk2) {
    const auto ahead = last_udp_cnt_ ? static_cast<std::int16_t>(packet_.udp_cnt - *last_udp_cnt_)
                                     : std::int16_t{1};
    if (last_udp_cnt_ && packet_.udp_cnt != 0 && ahead > 1) {
      counters_.sequence_gaps += static_cast<std::uint64_t>(ahead - 1);
    }
    if (!last_udp_cnt_ || ahead > 0 || packet_.udp_cnt == 0) last_udp_cnt_ = packet_.udp_cnt;
  } else if (last_packet_end_ns_ && !older) {
    // The next packet starts one point interval after the previous packet's last point.
    const std::int64_t expected = *last_packet_end_ns_ + model_.point_interval_ns;
    const std::int64_t late = packet_.timestamp_ns - expected;
    const std::int64_t span = static_cast<std::int64_t>(last_span_ns_) + model_.point_interval_ns;
    if (span > 0 && late > span / 2)
      counters_.sequence_gaps += static_cast<std::uint64_t>((late + span / 2) / span);
  }
  if (!older) {
    last_packet_end_ns_ = packet_.timestamp_ns + packet_.span_ns;
    last_span_ns_ = packet_.span_ns;
    last_packet_host_ns_ = packet.host_time_ns;
    last_time_type_ = packet_.time_type;
  }

  for (std::uint16_t i = 0; i < packet_.count; ++i) {
    const LivoxPoint& p = packet_.points[i];
    if (options_.drop_invalid_points && !p.valid) continue;
    if (options_.keep_first_return_only && p.return_index != 0) continue;
    const std::int64_t t = packet_.timestamp_ns + p.t_offset_ns;
    const std::int64_t index = floor_div(t, options_.scan_period_ns);
    if (index < newest_index_ && newest_index_ - index <= kClockResetWindows) {
      ++counters_.late_points;  // its scan was emitted already
      continue;
    }
    newest_index_ = index;
    if (scan_open_ && index != scan_index_) emit(sinks);
    if (!scan_open_) {
      scan_open_ = true;
      scan_index_ = index;
      scan_.clear();
      const std::int64_t start = index * options_.scan_period_ns;
      scan_.start.sensor = SensorTime(start);
      // Host time of the scan start: this packet's receive time, back-dated by how far the
      // point lies after the window start.
      scan_.start.host =
          HostTime(packet.host_time_ns - (t - start) - packet_.span_ns + p.t_offset_ns);
      scan_.start.mapped = MappedTime(scan_.start.host.ns);
    }
    scan_.push_back(p.x, p.y, p.z, p.reflectivity, p.line, p.return_index,
                    static_cast<std::int32_t>(t - scan_.start.sensor.ns), p.valid);
  }
}

void LivoxDecoder::emit(const drivers::DecoderSinks& sinks) {
  if (!scan_open_) return;
  scan_.sequence = next_sequence_++;
  ++counters_.scans;
  counters_.points += scan_.size();
  if (sinks.on_scan) sinks.on_scan(scan_);
  scan_open_ = false;
  scan_.clear();
}

void LivoxDecoder::flush(const drivers::DecoderSinks& sinks) {
  emit(sinks);
}

}  // namespace livod::livox
