#include "drivers/hesai/hesai_decoder.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/numeric.hpp"

namespace livod::drivers::hesai {
namespace {

constexpr int kTurn = 36000;  // 0.01 degree
// An azimuth step between firing rounds larger than twice the expected one plus this margin is a
// jump over the skipped sector of a start/end angle window.
constexpr double kJumpMarginCentideg = 100.0;
constexpr int kBackwardToleranceCentideg = 1000;
// Scans are reserved for 1/8 s of dual-return points, so that steady state does not allocate.
constexpr double kReservedScanSeconds = 0.125;

AngleCorrections load_for(const HesaiOptions& options) {
  if (!options.calibration_file) {
    throw Error("the " + std::string(traits(options.model).name) +
                " needs its angle correction file (calibration: the CSV exported by the sensor "
                "or PandarView)");
  }
  return load_angle_corrections(*options.calibration_file);
}

}  // namespace

HesaiDecoder::HesaiDecoder(const HesaiOptions& options, AngleCorrections corrections)
    : options_(options),
      traits_(traits(options.model)),
      corrections_(std::move(corrections)),
      timing_(options.model),
      geometry_(corrections_) {
  check_corrections_match(corrections_, options_.model);
  const auto rings = corrections_.rings();
  for (std::size_t c = 0; c < corrections_.channels.size(); ++c) {
    const ChannelCorrection& k = corrections_.channels[c];
    channels_.push_back(Channel{k.azimuth_deg * 100.0, rings[c]});
    min_correction_centideg_ = std::min(min_correction_centideg_, k.azimuth_deg * 100.0);
  }
  cut_centideg_ =
      static_cast<int>((std::lround(options_.cut_angle_deg * 100.0) % kTurn + kTurn) % kTurn);
  for (auto& a : assemblies_) {
    a.scan.reserve(
        static_cast<std::size_t>(traits_.points_per_second * 2.0 * kReservedScanSeconds));
  }
}

HesaiDecoder::HesaiDecoder(const HesaiOptions& options)
    : HesaiDecoder(options, load_for(options)) {}

std::string HesaiDecoder::model_name() const {
  return std::string(traits_.name);
}

void HesaiDecoder::on_packet(const PacketView& packet, const DecoderSinks& sinks) {
  ++counters_.packets;
  const auto payload = packet.payload;
  if (payload.size() == kGpsPacketSize && payload[0] == std::byte{0xFF} &&
      payload[1] == std::byte{0xEE}) {
    ++counters_.aux_packets;
    ++hesai_.gps_packets;
    return;
  }
  const PacketError error = decode_packet(options_.model, payload, packet_);
  if (error != PacketError::kNone) {
    ++counters_.decode_errors;
    ++hesai_.packet_errors[static_cast<std::size_t>(error)];
    return;
  }
  ++counters_.lidar_packets;
  hesai_.motor_rpm = packet_.motor_rpm;
  hesai_.return_mode = packet_.return_mode;
  if (packet_.high_temperature) ++hesai_.high_temperature_packets;
  if (!check_continuity(packet)) return;

  const bool dual = packet_.returns == 2;
  std::array<std::int32_t, kMaxBlocks> delay{};
  block_delays(dual, delay);
  // The packet leaves once its last round has fired: a point's receive time is the packet's less
  // the time from the point to then (a clock fed by scans alone would otherwise carry up to a
  // packet of accumulation, varying with where the scan was cut; docs/clocks.md).
  const std::int64_t rx_minus_sensor =
      packet.host_time_ns - packet_.timestamp_ns - timing_.last_firing_ns(dual);
  for (int b = 0; b < traits_.blocks; ++b) {
    add_block(b, dual, delay[static_cast<std::size_t>(b)], packet_.timestamp_ns, rx_minus_sensor,
              sinks);
  }
}

bool HesaiDecoder::check_continuity(const PacketView& packet) {
  const bool dual = packet_.returns == 2;
  if (have_previous_) {
    const std::int64_t dt = packet_.timestamp_ns - previous_packet_ns_;
    const std::int64_t host_advance =
        std::max<std::int64_t>(0, packet.host_time_ns - previous_host_ns_);
    // A sensor-time step the receive times cannot explain is the clock jumping (PTP or GPS
    // acquired or lost), not loss and not reordering.
    const bool jumped = dt < -kMaxReorderNs || dt > host_advance + kMaxUnexplainedAdvanceNs;
    std::int64_t missing = 0;
    if (packet_.udp_sequence && previous_udp_sequence_) {
      const std::uint32_t step = *packet_.udp_sequence - *previous_udp_sequence_;
      if (step == 0 || step >= 0x80000000U) {
        ++hesai_.late_packets;
        return false;
      }
      missing = static_cast<std::int64_t>(step) - 1;
    } else if (!jumped) {
      if (dt <= 0) {
        ++hesai_.late_packets;
        return false;
      }
      missing = std::llround(static_cast<double>(dt) /
                             static_cast<double>(timing_.packet_period_ns(dual))) -
                1;
    }
    if (jumped) ++counters_.clock_jumps;
    if (missing > 0 && options_.fov) {
      // The packets the skipped sector between the two packets would have held were never due.
      const int skipped =
          options_.fov->skipped_on_path_centideg(previous_last_azimuth_, packet_.azimuth[0]);
      const int rounds = traits_.blocks / packet_.returns;
      const int last = traits_.blocks - 1;
      const int advance =
          (kTurn + packet_.azimuth[static_cast<std::size_t>(last)] - packet_.azimuth[0]) % kTurn;
      if (skipped > 0 && rounds > 1 && advance > 0) {
        // Whether the sensor sends the packets that straddle the window's edges is not
        // documented: one more packet on each edge is no loss either.
        const double per_packet = advance / static_cast<double>(rounds - 1) * rounds;
        const auto explained = static_cast<std::int64_t>(std::ceil(skipped / per_packet)) + 2;
        missing = std::max<std::int64_t>(0, missing - explained);
      }
    }
    if (missing > 0) {
      counters_.sequence_gaps += static_cast<std::uint64_t>(missing);
      assemblies_[0].has_gap = true;
      assemblies_[1].has_gap = true;
    }
  }
  have_previous_ = true;
  previous_udp_sequence_ = packet_.udp_sequence;
  previous_packet_ns_ = packet_.timestamp_ns;
  previous_host_ns_ = packet.host_time_ns;
  previous_last_azimuth_ = packet_.azimuth[static_cast<std::size_t>(traits_.blocks - 1)];
  return true;
}

void HesaiDecoder::block_delays(bool dual, std::array<std::int32_t, kMaxBlocks>& delay) {
  // The packet time dates the last firing round. A round whose azimuth is far behind the next
  // round's was fired before the sensor crossed its skipped sector: earlier by that sector's time.
  if (packet_.motor_rpm == 0) return;
  const double rate = packet_.motor_rpm * static_cast<double>(kTurn) / 60e9;  // 0.01 deg per ns
  const int returns = dual ? 2 : 1;
  const int rounds = traits_.blocks / returns;
  std::int64_t shift = 0;
  bool jumped = false;
  for (int r = rounds - 1; r >= 1; --r) {
    const int b = r * returns;
    const int previous = b - returns;
    const int step = (kTurn + packet_.azimuth[static_cast<std::size_t>(b)] -
                      packet_.azimuth[static_cast<std::size_t>(previous)]) %
                     kTurn;
    const double expected =
        rate * (timing_.block_start_ns(dual, b) - timing_.block_start_ns(dual, previous));
    if (step > 2.0 * expected + kJumpMarginCentideg && step < kTurn - kBackwardToleranceCentideg) {
      shift -= std::llround((step - expected) / rate);
      jumped = true;
    }
    for (int k = previous; k < b; ++k)
      delay[static_cast<std::size_t>(k)] = static_cast<std::int32_t>(shift);
  }
  if (jumped) ++hesai_.fov_boundary_packets;
}

void HesaiDecoder::add_block(int block, bool dual, std::int32_t delay, std::int64_t packet_ns,
                             std::int64_t rx_minus_sensor, const DecoderSinks& sinks) {
  const std::uint16_t azimuth = packet_.azimuth[static_cast<std::size_t>(block)];
  const int phase = (kTurn + azimuth - cut_centideg_) % kTurn;
  const std::int64_t block_start = packet_ns + timing_.block_start_ns(dual, block) + delay;
  const bool by_time = options_.cut == ScanCut::kTimePeriod;
  if (by_time) {
    const std::int64_t index = floor_div(block_start, options_.cut_period_ns);
    if (!have_period_) {
      have_period_ = true;
      period_index_ = index;
    } else if (index != period_index_) {
      period_index_ = index;
      emit(assemblies_[static_cast<std::size_t>(current_)], sinks, true);
      assemblies_[static_cast<std::size_t>(current_)].started_at_cut = true;
    }
  } else if (!have_phase_) {
    have_phase_ = true;
    block_turn_ = 0;
    last_phase_ = phase;
    turn_ = phase + min_correction_centideg_ < 0.0 ? -1 : 0;
  } else {
    // Passed the cut angle: the phase went down although the head moved forward (by less than
    // almost a turn: a small step back is jitter, not a turn). The forward move may be long,
    // through a skipped sector or a loss.
    const int forward = (kTurn + phase - last_phase_) % kTurn;
    if (phase < last_phase_ && forward < kTurn - kBackwardToleranceCentideg) ++block_turn_;
    last_phase_ = phase;
  }
  // A scan that spans too long (a stopped or stalling motor) is closed, incomplete.
  for (auto& a : assemblies_) {
    if (!a.scan.empty() && block_start - a.scan.start.sensor.ns > kMaxScanSpanNs) {
      emit(a, sinks, false);
    }
  }

  const BlockAngle angle = block_angle(azimuth);
  const int partner = dual ? (block ^ 1) : block;
  const bool second_of_pair = dual && (block % 2) == 1;
  for (int c = 0; c < traits_.channels; ++c) {
    const std::uint16_t raw = packet_.raw_distance(block, c);
    if (raw == 0) {
      ++hesai_.zero_ranges;
      continue;
    }
    const std::uint8_t reflectivity = packet_.raw_reflectivity(block, c);
    std::uint8_t return_index = 0;
    if (dual) {
      const std::uint16_t partner_raw = packet_.raw_distance(partner, c);
      if (partner_raw == raw) {
        if (second_of_pair) {
          ++hesai_.duplicate_returns;
          continue;
        }
      } else if (partner_raw != 0) {
        const std::uint8_t partner_reflectivity = packet_.raw_reflectivity(partner, c);
        const bool stronger = reflectivity > partner_reflectivity ||
                              (reflectivity == partner_reflectivity && raw < partner_raw);
        return_index = stronger ? 0 : 1;
      }
    }
    const double d = raw * packet_.distance_unit_m;
    if (d <= options_.min_range_m || d > options_.max_range_m) {
      ++hesai_.out_of_range;
      continue;
    }
    const Channel& ch = channels_[static_cast<std::size_t>(c)];
    double px = 0.0;
    double py = 0.0;
    double pz = 0.0;
    geometry_.point(angle, c, d, px, py, pz);
    const auto x = static_cast<float>(px);
    const auto y = static_cast<float>(py);
    const auto z = static_cast<float>(pz);
    const std::int64_t t = packet_ns + timing_.offset_ns(dual, block, c) + delay;

    Assembly* target = &assemblies_[static_cast<std::size_t>(current_)];
    if (!by_time) {
      const double unwrapped =
          static_cast<double>(block_turn_) * kTurn + phase + ch.azimuth_centideg;
      const auto turn = static_cast<std::int64_t>(std::floor(unwrapped / kTurn));
      if (turn < turn_) {
        ++counters_.late_points;  // its turn was emitted already
        continue;
      }
      while (turn > turn_ + 1) advance_turn(sinks);
      if (turn == turn_ + 1) target = &assemblies_[static_cast<std::size_t>(1 - current_)];
    }
    append(*target, block_start, rx_minus_sensor, t, x, y, z, static_cast<float>(reflectivity),
           ch.ring, return_index);
  }
  // Every point of the open turn has come once this block's smallest angle is past the cut.
  if (!by_time && static_cast<double>(block_turn_) * kTurn + phase + min_correction_centideg_ >=
                      static_cast<double>(turn_ + 1) * kTurn) {
    advance_turn(sinks);
  }
}

void HesaiDecoder::append(Assembly& a, std::int64_t block_start_ns, std::int64_t rx_minus_sensor,
                          std::int64_t t_ns, float x, float y, float z, float intensity,
                          std::uint16_t ring, std::uint8_t return_index) {
  LidarScan& s = a.scan;
  if (s.empty()) {
    s.start.sensor = SensorTime(block_start_ns);
    s.start.host = HostTime(rx_minus_sensor + block_start_ns);
    s.start.mapped = MappedTime(s.start.host.ns);  // placeholder, see header
  }
  const std::int64_t offset = t_ns - s.start.sensor.ns;
  if (offset < 0 || offset > std::numeric_limits<std::int32_t>::max()) {
    ++counters_.late_points;
    return;
  }
  s.push_back(x, y, z, intensity, ring, return_index, static_cast<std::int32_t>(offset), true);
}

void HesaiDecoder::advance_turn(const DecoderSinks& sinks) {
  emit(assemblies_[static_cast<std::size_t>(current_)], sinks, true);
  current_ = 1 - current_;
  assemblies_[static_cast<std::size_t>(current_)].started_at_cut = true;
  ++turn_;
}

void HesaiDecoder::emit(Assembly& a, const DecoderSinks& sinks, bool complete) {
  if (!a.scan.empty()) {
    a.scan.sequence = next_sequence_++;
    ++counters_.scans;
    counters_.points += a.scan.size();
    if (!complete || !a.started_at_cut || a.has_gap) ++counters_.incomplete_scans;
    if (sinks.on_scan) sinks.on_scan(a.scan);
    a.scan.clear();
  }
  a.has_gap = false;
  a.started_at_cut = false;
}

void HesaiDecoder::flush(const DecoderSinks& sinks) {
  emit(assemblies_[static_cast<std::size_t>(current_)], sinks, false);
  emit(assemblies_[static_cast<std::size_t>(1 - current_)], sinks, false);
}

}  // namespace livod::drivers::hesai
