#include "drivers/ouster/ouster_decoder.hpp"

#include <algorithm>
#include <limits>
#include <utility>

#include "core/error.hpp"
#include "drivers/ouster/ouster_family.hpp"

namespace livod::drivers::ouster {
namespace {

// Per-point offsets are int32 ns (core/measurement.hpp): a column further than this from its
// frame's first column is a clock jump, not a measurement of this frame.
constexpr std::int64_t kMaxPointOffsetNs = std::numeric_limits<std::int32_t>::max();

// parse_metadata() guarantees all of this; a hand-built SensorMetadata may not.
const SensorMetadata& checked(const SensorMetadata& m) {
  const DataFormat& f = m.format;
  const bool ok = f.pixels_per_column > 0 && f.columns_per_packet > 0 && f.columns_per_frame > 0 &&
                  f.columns_per_frame % f.columns_per_packet == 0 &&
                  m.beam_altitude_angles_deg.size() == f.pixels_per_column &&
                  m.beam_azimuth_angles_deg.size() == f.pixels_per_column &&
                  f.column_window.first < f.columns_per_frame &&
                  f.column_window.last < f.columns_per_frame;
  if (!ok) throw livod::Error("Ouster metadata is inconsistent (beams, data format or window)");
  return m;
}

// A packet's columns span at most 16 columns of the slowest mode (512x10: 3.1 ms); a longer or
// negative span is a corrupt timestamp (counted as a timestamp jump where it is used).
constexpr std::int64_t kMaxPacketSpanNs = 10'000'000;

// Time from column time `ts` to the packet's last valid column (invalid columns may carry no
// timestamp): how long the packet waited after `ts` before it could leave; 0 if corrupt.
std::int64_t accumulation_after_ns(const LidarPacket& packet, std::uint64_t ts) {
  for (std::uint32_t c = packet.columns(); c-- > 0;) {
    if (!packet.column_valid(c)) continue;
    const auto span = static_cast<std::int64_t>(packet.column_timestamp_ns(c) - ts);
    return span >= 0 && span <= kMaxPacketSpanNs ? span : 0;
  }
  return 0;
}

}  // namespace

OusterDecoder::OusterDecoder(SensorMetadata metadata, OusterDecoderOptions options)
    : metadata_(std::move(metadata)),
      options_(options),
      format_(PacketFormat::from_metadata(checked(metadata_), options_.crc)),
      lut_(metadata_) {
  const ColumnWindow& w = metadata_.format.column_window;
  const std::uint32_t columns = format_.columns_per_frame;
  window_size_ = (w.last + columns - w.first) % columns + 1;
  // Columns are measured in increasing measurement_id order from column 0. A window that wraps
  // through 0 is measured as [0, last] then [first, W-1].
  last_column_in_time_ = w.first <= w.last ? w.last : columns - 1;
  for (std::uint32_t first = 0; first < columns; first += format_.columns_per_packet) {
    for (std::uint32_t c = first; c < first + format_.columns_per_packet; ++c) {
      if (in_window(c)) {
        ++window_packet_slots_;
        break;
      }
    }
  }
  current_init_id_ = metadata_.initialization_id;
  scan_.reserve(static_cast<std::size_t>(format_.pixels_per_column) * columns * format_.returns());
}

std::vector<std::uint16_t> OusterDecoder::default_ports() const {
  std::vector<std::uint16_t> ports;
  // Without ports in the metadata: the family table's defaults (ouster_family.cpp).
  const UdpPorts& defaults = ouster_family().models.front().ports;
  const std::uint16_t lidar = metadata_.udp_port_lidar.value_or(defaults.lidar);
  const std::uint16_t imu = metadata_.udp_port_imu.value_or(defaults.imu);
  // Port 0 means "stream disabled" in the sensor config (e.g. imu_zm_no_lidar).
  if (lidar != 0) ports.push_back(lidar);
  if (imu != 0 && imu != lidar) ports.push_back(imu);
  return ports;
}

std::string OusterDecoder::model_name() const {
  return metadata_.prod_line.empty() ? std::string("Ouster") : "Ouster " + metadata_.prod_line;
}

bool OusterDecoder::in_window(std::uint32_t column) const {
  const ColumnWindow& w = metadata_.format.column_window;
  return w.first <= w.last ? (column >= w.first && column <= w.last)
                           : (column >= w.first || column <= w.last);
}

std::uint32_t OusterDecoder::window_columns_before(std::uint32_t column) const {
  const ColumnWindow& w = metadata_.format.column_window;
  if (w.first <= w.last) {
    if (column <= w.first) return 0;
    return std::min(column, w.last + 1) - w.first;
  }
  // [0, last] then [first, W-1] in measurement order.
  const std::uint32_t low = std::min(column, w.last + 1);
  const std::uint32_t high = column > w.first ? column - w.first : 0;
  return low + high;
}

std::uint32_t OusterDecoder::window_packets_before(std::uint32_t packet) const {
  std::uint32_t n = 0;
  const std::uint32_t per_packet = format_.columns_per_packet;
  for (std::uint32_t p = 0; p < packet; ++p) {
    for (std::uint32_t c = p * per_packet; c < (p + 1) * per_packet; ++c) {
      if (in_window(c)) {
        ++n;
        break;
      }
    }
  }
  return n;
}

void OusterDecoder::count_error(PacketError error) {
  ++counters_.decode_errors;
  switch (error) {
    case PacketError::kWrongSize:
      ++ouster_counters_.wrong_size;
      break;
    case PacketError::kWrongPacketType:
      ++ouster_counters_.wrong_packet_type;
      break;
    case PacketError::kCrcMismatch:
      ++ouster_counters_.crc_failures;
      break;
    case PacketError::kMeasurementIdOutOfRange:
    case PacketError::kInconsistentMeasurementIds:
      ++ouster_counters_.bad_measurement_ids;
      break;
    case PacketError::kNone:
      break;
  }
}

void OusterDecoder::on_packet(const PacketView& packet, const DecoderSinks& sinks) {
  ++counters_.packets;
  switch (classify_packet(packet.payload, format_)) {
    case PacketKind::kLidar:
      on_lidar(packet, sinks);
      return;
    case PacketKind::kImu:
      on_imu(packet, sinks);
      return;
    case PacketKind::kZone: {
      PacketHeader header;
      const PacketError error = check_zone_packet(packet.payload, format_, header);
      if (error != PacketError::kNone) {
        count_error(error);
      } else {
        ++counters_.aux_packets;
        ++ouster_counters_.zone_packets;
      }
      return;
    }
    case PacketKind::kUnknown: {
      // A size nothing here has, or a header with an unexpected type. When the firmware writes
      // CRCs, a packet of a known size with a bad CRC is corruption rather than a foreign type.
      const std::size_t n = packet.payload.size();
      const bool known_size = n == format_.lidar_packet_size || n == format_.imu_packet_size ||
                              n == format_.zone_packet_size;
      const bool has_header =
          n >= kPacketHeaderSize + kPacketFooterSize &&
          (!format_.legacy_lidar() || format_.imu_profile != ImuProfile::kLegacy);
      if (!has_header) {
        count_error(PacketError::kWrongSize);
      } else if (known_size && (format_.lidar_crc || format_.imu_crc) &&
                 !crc_matches(packet.payload)) {
        count_error(PacketError::kCrcMismatch);
      } else {
        count_error(PacketError::kWrongPacketType);
      }
      return;
    }
  }
}

void OusterDecoder::on_imu(const PacketView& packet, const DecoderSinks& sinks) {
  const PacketError error = parse_imu_packet(packet.payload, format_, imu_packet_);
  if (error != PacketError::kNone) {
    count_error(error);
    return;
  }
  if (format_.imu_profile != ImuProfile::kLegacy && options_.check_serial_number &&
      metadata_.prod_sn_number && imu_packet_.header.prod_sn != *metadata_.prod_sn_number) {
    ++counters_.decode_errors;
    ++ouster_counters_.serial_mismatches;
    return;
  }
  ++counters_.imu_packets;
  for (std::size_t i = 0; i < imu_packet_.count; ++i) {
    const ImuMeasurement& m = imu_packet_.measurements[i];
    if (!m.valid) {
      ++ouster_counters_.invalid_imu_samples;
      continue;
    }
    imu_sample_.stamp.sensor = SensorTime(static_cast<std::int64_t>(m.timestamp_ns));
    imu_sample_.stamp.host = HostTime(packet.host_time_ns);
    imu_sample_.stamp.mapped = MappedTime(packet.host_time_ns);
    imu_sample_.accel_m_s2 = m.accel_m_s2;
    imu_sample_.gyro_rad_s = m.gyro_rad_s;
    ++ouster_counters_.imu_samples;
    if (sinks.on_imu) sinks.on_imu(imu_sample_);
  }
}

void OusterDecoder::on_lidar(const PacketView& packet, const DecoderSinks& sinks) {
  LidarPacket lp;
  const PacketError error = LidarPacket::parse(packet.payload, format_, lp);
  if (error != PacketError::kNone) {
    count_error(error);
    return;
  }
  const PacketHeader& h = lp.header();
  if (!format_.legacy_lidar()) {
    if (options_.check_serial_number && metadata_.prod_sn_number &&
        h.prod_sn != *metadata_.prod_sn_number) {
      ++counters_.decode_errors;
      ++ouster_counters_.serial_mismatches;
      return;
    }
    if (metadata_.initialization_id && h.init_id != *metadata_.initialization_id) {
      metadata_init_id_mismatch_ = true;
    }
    if (current_init_id_ && h.init_id != *current_init_id_) {
      // The sensor re-initialised: the partial frame and the frame-id history belong to the
      // previous run.
      ++ouster_counters_.init_id_changes;
      discard_frame();
      last_closed_frame_id_.reset();
    }
    current_init_id_ = h.init_id;
    status_.alert_flags = h.alert_flags;
    status_.countdown_thermal_shutdown = h.countdown_thermal_shutdown;
    status_.countdown_shot_limiting = h.countdown_shot_limiting;
    status_.thermal_shutdown = h.thermal_shutdown;
    status_.shot_limiting = h.shot_limiting;
    status_.init_id = h.init_id;
    if (h.thermal_shutdown != 0) ++ouster_counters_.thermal_shutdown_packets;
    if (h.shot_limiting != 0) ++ouster_counters_.shot_limiting_packets;
  }
  status_.frame_id = h.frame_id;
  ++counters_.lidar_packets;

  const std::uint32_t first_column = lp.measurement_id(0);
  const std::uint32_t last_column = first_column + format_.columns_per_packet - 1;
  const std::uint64_t modulus = format_.frame_id_modulus();
  // Frame ids only move forward (modulo wrap-around): a "step" of more than half the range is a
  // packet from an earlier frame that arrived late.
  const auto frames_ahead = [&](std::uint32_t from) {
    return (h.frame_id + modulus - from) % modulus;
  };
  if (frame_.open && h.frame_id != frame_.frame_id) {
    if (frames_ahead(frame_.frame_id) > modulus / 2) {
      ++ouster_counters_.late_packets;
      return;
    }
    close_frame(sinks);
  }
  if (!frame_.open) {
    if (last_closed_frame_id_) {
      const std::uint64_t step = frames_ahead(*last_closed_frame_id_);
      if (step == 0 || step > modulus / 2) {
        ++ouster_counters_.late_packets;  // its frame was already emitted
        return;
      }
      ouster_counters_.frame_id_gaps += step - 1;
      counters_.sequence_gaps += (step - 1) * window_packet_slots_;
    }
    open_frame(h.frame_id);
  } else if (first_column < frame_.next_measurement_id) {
    ++ouster_counters_.late_packets;  // duplicate or reordered packet of the open frame
    return;
  }
  add_columns(lp, packet.host_time_ns);
  frame_.next_measurement_id = last_column + 1;
  if (last_column >= last_column_in_time_ && first_column <= last_column_in_time_) {
    close_frame(sinks);
  }
}

void OusterDecoder::open_frame(std::uint32_t frame_id) {
  frame_ = Frame{};
  frame_.open = true;
  frame_.frame_id = frame_id;
  frame_.continues = last_closed_frame_id_.has_value();
  scan_.clear();
}

void OusterDecoder::add_columns(const LidarPacket& packet, std::int64_t host_time_ns) {
  const std::uint32_t rows = format_.pixels_per_column;
  const ProfileLayout& layout = *format_.layout;
  const FieldLayout& range1 = layout.field(ChannelField::kRange);
  const FieldLayout& range2 = layout.field(ChannelField::kRange2);
  const FieldLayout& refl1 = layout.field(ChannelField::kReflectivity);
  const FieldLayout& refl2 = layout.field(ChannelField::kReflectivity2);
  const bool dual = layout.returns == 2;
  const bool keep_invalid = options_.keep_invalid_points;

  bool packet_in_window = false;
  for (std::uint32_t c = 0; c < packet.columns(); ++c) {
    const std::uint32_t v = packet.measurement_id(c);
    const bool valid = packet.column_valid(c);
    if (in_window(v)) {
      packet_in_window = true;
      ++frame_.window_columns;
      if (!valid) ++ouster_counters_.invalid_columns;
    }
    std::int32_t offset_ns = frame_.last_offset_ns;
    if (valid) {
      // Invalid columns may carry no timestamp, so only valid ones define the scan start and
      // their own offsets; kept invalid pixels reuse the latest valid offset.
      const std::uint64_t ts = packet.column_timestamp_ns(c);
      if (!frame_.have_start) {
        frame_.have_start = true;
        frame_.start_ts_ns = ts;
        scan_.start.sensor = SensorTime(static_cast<std::int64_t>(ts));
        // The packet leaves once its last column is measured: back-dated by the columns from
        // this one on, its receive time is this column's (a clock fed by scans alone would
        // otherwise carry a packet of accumulation, 1.5 ms at 1024x10; docs/clocks.md).
        scan_.start.host = HostTime(host_time_ns - accumulation_after_ns(packet, ts));
        scan_.start.mapped = MappedTime(scan_.start.host.ns);
      }
      const std::int64_t offset =
          static_cast<std::int64_t>(ts) - static_cast<std::int64_t>(frame_.start_ts_ns);
      if (offset > kMaxPointOffsetNs || offset < -kMaxPointOffsetNs) {
        ++ouster_counters_.timestamp_jumps;
        continue;
      }
      offset_ns = static_cast<std::int32_t>(offset);
      frame_.last_offset_ns = offset_ns;
      ++frame_.valid_columns;
    } else if (!keep_invalid) {
      continue;
    }
    std::uint64_t points = 0;
    for (std::uint32_t u = 0; u < rows; ++u) {
      const std::byte* block = packet.channel_block(c, u);
      const auto ring = static_cast<std::uint16_t>(u);
      const std::uint32_t r1 = valid ? read_field(block, range1) : 0;
      if (r1 != 0) {
        const Eigen::Vector3f p = lut_.point(u, v, r1);
        scan_.push_back(p.x(), p.y(), p.z(), static_cast<float>(read_field(block, refl1)), ring, 0,
                        offset_ns, true);
        ++points;
      } else if (keep_invalid) {
        scan_.push_back(0.0F, 0.0F, 0.0F, 0.0F, ring, 0, offset_ns, false);
      }
      if (dual) {
        const std::uint32_t r2 = valid ? read_field(block, range2) : 0;
        if (r2 != 0) {
          const Eigen::Vector3f p = lut_.point(u, v, r2);
          scan_.push_back(p.x(), p.y(), p.z(), static_cast<float>(read_field(block, refl2)), ring,
                          1, offset_ns, true);
          ++points;
        } else if (keep_invalid) {
          scan_.push_back(0.0F, 0.0F, 0.0F, 0.0F, ring, 1, offset_ns, false);
        }
      }
    }
    frame_.valid_points += points;
  }
  if (packet_in_window) {
    ++frame_.window_packets;
    const std::uint32_t index = packet.measurement_id(0) / format_.columns_per_packet;
    if (!frame_.have_window_packet) frame_.first_window_packet = index;
    frame_.have_window_packet = true;
    frame_.last_window_packet = index;
  }
}

void OusterDecoder::close_frame(const DecoderSinks& sinks, bool at_end) {
  if (!frame_.open) return;
  frame_.open = false;
  last_closed_frame_id_ = frame_.frame_id;
  const bool complete = frame_.window_columns >= window_size_;
  if (!complete) {
    ++counters_.incomplete_scans;
    // Columns and packets that were due: not those before the first packet of a capture (or of
    // a run after a re-init), nor those after the last packet of a capture.
    std::uint32_t due_columns = window_size_;
    std::uint32_t due_packets = window_packet_slots_;
    if (frame_.have_window_packet) {
      const std::uint32_t per_packet = format_.columns_per_packet;
      if (!frame_.continues) {
        due_columns -= window_columns_before(frame_.first_window_packet * per_packet);
        due_packets -= window_packets_before(frame_.first_window_packet);
      }
      if (at_end) {
        const std::uint32_t end_packet = frame_.last_window_packet + 1;
        due_columns -= window_size_ - window_columns_before(end_packet * per_packet);
        due_packets -= window_packet_slots_ - window_packets_before(end_packet);
      }
    } else if (!frame_.continues || at_end) {
      due_columns = 0;
      due_packets = 0;
    }
    if (frame_.window_columns < due_columns) {
      ouster_counters_.missing_columns += due_columns - frame_.window_columns;
    }
    if (frame_.window_packets < due_packets) {
      counters_.sequence_gaps += due_packets - frame_.window_packets;
    }
  }
  if (frame_.valid_columns == 0) {
    scan_.clear();
    return;  // nothing measured: no scan to publish
  }
  if (!complete && options_.incomplete_scans == IncompleteScanPolicy::kDrop) {
    ++ouster_counters_.dropped_incomplete_scans;
    scan_.clear();
    return;
  }
  scan_.sequence = scan_sequence_++;
  ++counters_.scans;
  counters_.points += frame_.valid_points;
  if (sinks.on_scan) sinks.on_scan(scan_);
  scan_.clear();
}

void OusterDecoder::discard_frame() {
  if (!frame_.open) return;
  frame_.open = false;
  ++counters_.incomplete_scans;
  ++ouster_counters_.dropped_incomplete_scans;
  scan_.clear();
}

void OusterDecoder::flush(const DecoderSinks& sinks) {
  close_frame(sinks, true);
}

}  // namespace livod::drivers::ouster
