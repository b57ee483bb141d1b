#include "drivers/velodyne/data_packet.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kCentidegToRad = kPi / 18000.0;
// Rotation rates above 30 rev/s do not exist (the fastest Velodyne spins at 20 Hz); a larger
// in-packet rate means the azimuth went backwards (a stationary or stopping head).
constexpr double kMaxRateCentidegPerNs = 30.0 * 36000.0 * 1e-9;
constexpr int kVeloViewMedianIndex = wire::kBlocksPerPacket / 2;
// An azimuth step between firing sequences larger than twice the expected one plus this margin is
// a jump (the skipped sector of a reduced field of view); steps that look like a small backward
// move (a slowing or stationary head) are not.
constexpr double kJumpMarginCentideg = 100.0;
constexpr int kBackwardToleranceCentideg = 1000;
// Below 1 rev/s the rate cannot date the blocks after a jump.
constexpr double kMinDatingRateCentidegPerNs = 36000.0 * 1e-9;
constexpr std::int64_t kUndatable = std::numeric_limits<std::int64_t>::min();

// cos/sin of a small angle (|d| < 0.03 rad here): the series error is below 1e-15.
inline void small_angle_cos_sin(double d, double& c, double& s) {
  const double d2 = d * d;
  c = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)));
  s = d * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0)));
}

// VeloView's vtkMath::Round.
inline int veloview_round(double f) {
  return static_cast<int>(f + (f >= 0.0 ? 0.5 : -0.5));
}

bool is_bank_flag(std::uint16_t flag) {
  return flag == wire::kBank0Flag || flag == wire::kBank1Flag || flag == wire::kBank2Flag ||
         flag == wire::kBank3Flag;
}

}  // namespace

DataPacketDecoder::DataPacketDecoder(Model model, const Calibration& calibration,
                                     DecodeSettings settings)
    : model_(model),
      settings_(settings),
      timing_(model, settings.vls128_channel_us),
      distance_unit_m_(traits(model).distance_unit_m) {
  check_calibration_matches(calibration, model);
  if (settings_.azimuth == AzimuthInterpolation::kVeloView && model != Model::kVlp16 &&
      model != Model::kHdl32e) {
    throw Error("VeloView azimuth interpolation is only defined for the VLP-16 and HDL-32E");
  }
  const auto rings = calibration.rings();
  lasers_.reserve(calibration.lasers.size());
  for (std::size_t i = 0; i < calibration.lasers.size(); ++i) {
    const auto& l = calibration.lasers[i];
    lasers_.push_back(LaserTable{std::cos(l.vert_correction_rad), std::sin(l.vert_correction_rad),
                                 std::cos(l.rot_correction_rad), std::sin(l.rot_correction_rad),
                                 l.rot_correction_rad, l.rot_correction_rad * 180.0 / kPi,
                                 l.dist_correction_m, l.vert_offset_m, l.horiz_offset_m, rings[i]});
  }
}

int DataPacketDecoder::laser_of(std::uint16_t flag, int channel) const {
  switch (model_) {
    case Model::kVlp16:
    case Model::kPuckHiRes:
      return channel % 16;  // two firing sequences of 16 lasers per block
    case Model::kVlp32c:
    case Model::kHdl32e:
      return channel;
    case Model::kVls128: {
      int bank = 0;
      if (flag == wire::kBank1Flag) bank = 1;
      if (flag == wire::kBank2Flag) bank = 2;
      if (flag == wire::kBank3Flag) bank = 3;
      return 32 * bank + channel;
    }
  }
  return channel;
}

double DataPacketDecoder::veloview_azimuth_diff(const DataPacketResult& r) const {
  // VeloView: the 7th smallest of the 11 adjacent differences (nth_element at index 6).
  std::array<int, wire::kBlocksPerPacket - 1> diffs{};
  for (int b = 0; b + 1 < wire::kBlocksPerPacket; ++b) {
    diffs[static_cast<std::size_t>(b)] = (36000 + r.block_azimuth[static_cast<std::size_t>(b + 1)] -
                                          r.block_azimuth[static_cast<std::size_t>(b)]) %
                                         36000;
  }
  std::nth_element(diffs.begin(), diffs.begin() + kVeloViewMedianIndex, diffs.end());
  return diffs[kVeloViewMedianIndex];
}

std::optional<double> DataPacketDecoder::median_sequence_rate(const DataPacketResult& r) const {
  std::array<double, wire::kBlocksPerPacket> rates{};
  std::size_t n = 0;
  for (int b = 1; b < r.blocks_used; ++b) {
    const std::int32_t dt =
        timing_.block_reference_ns(r.dual, b) - timing_.block_reference_ns(r.dual, b - 1);
    if (dt <= 0) continue;
    const int step = (36000 + r.block_azimuth[static_cast<std::size_t>(b)] -
                      r.block_azimuth[static_cast<std::size_t>(b - 1)]) %
                     36000;
    if (step >= 36000 - kBackwardToleranceCentideg) continue;
    rates[n++] = step / static_cast<double>(dt);
  }
  if (n < 3) return std::nullopt;
  std::nth_element(rates.begin(), rates.begin() + static_cast<std::ptrdiff_t>(n / 2),
                   rates.begin() + static_cast<std::ptrdiff_t>(n));
  return rates[n / 2];
}

DataPacketResult DataPacketDecoder::decode(std::span<const std::byte> payload, double fallback_rate,
                                           std::span<DecodedReturn> out, double dating_rate) const {
  DataPacketResult r;
  if (payload.size() != wire::kDataPacketSize || out.size() < kMaxReturns) return r;

  r.toh_us = wire::u32le(payload, wire::kTimestampOffset);
  r.return_mode_byte = wire::u8(payload, wire::kReturnModeOffset);
  r.factory_byte = wire::u8(payload, wire::kFactoryByteOffset);
  if (r.toh_us >= wire::kMicrosecondsPerHour) {
    r.status = DataDecodeStatus::kBadTimestamp;
    return r;
  }
  r.dual = r.return_mode_byte == static_cast<std::uint8_t>(ReturnMode::kDual);
  r.blocks_used = timing_.blocks_used(r.dual);

  std::array<std::uint16_t, wire::kBlocksPerPacket> flags{};
  for (int b = 0; b < r.blocks_used; ++b) {
    const std::size_t base = static_cast<std::size_t>(b) * wire::kBlockSize;
    const std::uint16_t flag = wire::u16le(payload, base);
    const bool flag_ok = model_ == Model::kVls128 ? is_bank_flag(flag) : flag == wire::kBank0Flag;
    if (!flag_ok) {
      r.status = DataDecodeStatus::kBadBlockFlag;
      return r;
    }
    const std::uint16_t azimuth = wire::u16le(payload, base + 2);
    // Sensors occasionally send 36000 (= 360.00 degrees); it is kept as is so that the scan cut
    // sees the same sequence as VeloView, and is 0 degrees for the geometry.
    if (azimuth > wire::kAzimuthUnitsPerTurn) {
      r.status = DataDecodeStatus::kBadAzimuth;
      return r;
    }
    flags[static_cast<std::size_t>(b)] = flag;
    r.block_azimuth[static_cast<std::size_t>(b)] = azimuth;
  }

  // Azimuth discontinuities between consecutive firing sequences (a reduced field of view), and
  // the rotation rate. Without a jump the rate is the mean from the first block to the last
  // block of a later firing sequence; with one, the median of the per-sequence rates (the jump
  // would inflate the mean).
  double rate = std::isfinite(fallback_rate) ? fallback_rate : 0.0;
  const std::optional<double> median_rate = median_sequence_rate(r);
  const double reference_rate = median_rate.value_or(rate);
  const double date_with = std::isfinite(dating_rate) && dating_rate > kMinDatingRateCentidegPerNs
                               ? dating_rate
                               : reference_rate;
  std::int64_t delay_ns = 0;
  for (int b = 1; b < r.blocks_used; ++b) {
    const std::int32_t dt =
        timing_.block_reference_ns(r.dual, b) - timing_.block_reference_ns(r.dual, b - 1);
    if (dt > 0) {
      const int step = (36000 + r.block_azimuth[static_cast<std::size_t>(b)] -
                        r.block_azimuth[static_cast<std::size_t>(b - 1)]) %
                       36000;
      const double expected = reference_rate * dt;
      if (step > 2.0 * expected + kJumpMarginCentideg &&
          step < 36000 - kBackwardToleranceCentideg) {
        ++r.azimuth_jumps;
        r.jump_from_azimuth = r.block_azimuth[static_cast<std::size_t>(b - 1)];
        r.jump_to_azimuth = r.block_azimuth[static_cast<std::size_t>(b)];
        if (date_with > kMinDatingRateCentidegPerNs) {
          delay_ns += std::llround((step - date_with * dt) / date_with);
        } else {
          delay_ns = kUndatable;
        }
      }
    }
    r.block_delay_ns[static_cast<std::size_t>(b)] =
        delay_ns == kUndatable || delay_ns > std::numeric_limits<std::int32_t>::max() / 2
            ? kUndatableDelay
            : static_cast<std::int32_t>(delay_ns);
  }
  const int last = r.blocks_used - 1;
  if (r.azimuth_jumps > 0) {
    if (median_rate && *median_rate <= kMaxRateCentidegPerNs) {
      r.azimuth_rate = median_rate;
      rate = *median_rate;
    }
  } else {
    const std::int32_t span_ns =
        timing_.block_reference_ns(r.dual, last) - timing_.block_reference_ns(r.dual, 0);
    if (span_ns > 0) {
      const int diff =
          (36000 + r.block_azimuth[static_cast<std::size_t>(last)] - r.block_azimuth[0]) % 36000;
      const double measured = diff / static_cast<double>(span_ns);
      if (measured <= kMaxRateCentidegPerNs) {
        r.azimuth_rate = measured;
        rate = measured;
      }
    }
  }
  const double rate_rad_per_ns = rate * kCentidegToRad;
  const bool veloview = settings_.azimuth == AzimuthInterpolation::kVeloView;
  const double veloview_diff = veloview ? veloview_azimuth_diff(r) : 0.0;

  std::size_t n = 0;
  for (int b = 0; b < r.blocks_used; ++b) {
    r.block_begin[static_cast<std::size_t>(b)] = static_cast<std::uint16_t>(n);
    const std::int32_t block_delay = r.block_delay_ns[static_cast<std::size_t>(b)];
    if (block_delay == kUndatableDelay) {
      ++r.undated_blocks;
      continue;
    }
    r.last_block_time_ns = timing_.block_reference_ns(r.dual, b) + block_delay;
    r.last_block_azimuth = r.block_azimuth[static_cast<std::size_t>(b)];
    const std::size_t base = static_cast<std::size_t>(b) * wire::kBlockSize;
    const std::uint16_t block_azimuth = r.block_azimuth[static_cast<std::size_t>(b)];
    const double theta = block_azimuth * kCentidegToRad;
    const double cos_theta = std::cos(theta);
    const double sin_theta = std::sin(theta);
    const std::int32_t reference_ns = timing_.block_reference_ns(r.dual, b);
    const bool has_partner = r.dual;
    const int partner = b ^ 1;
    const std::size_t partner_base = static_cast<std::size_t>(partner) * wire::kBlockSize;

    for (int c = 0; c < wire::kChannelsPerBlock; ++c) {
      const std::size_t at = base + 4 + static_cast<std::size_t>(c) * wire::kChannelSize;
      const std::uint16_t raw = wire::u16le(payload, at);
      if (raw == 0) {
        ++r.zero_ranges;
        continue;
      }
      const std::uint8_t intensity = wire::u8(payload, at + 2);
      std::uint8_t return_index = 0;
      if (has_partner) {
        const std::size_t partner_at =
            partner_base + 4 + static_cast<std::size_t>(c) * wire::kChannelSize;
        const std::uint16_t partner_raw = wire::u16le(payload, partner_at);
        if (partner_raw == raw) {
          if ((b & 1) != 0) {  // the odd block repeats the even block's single return
            ++r.duplicates;
            continue;
          }
        } else if (partner_raw != 0) {
          const std::uint8_t partner_intensity = wire::u8(payload, partner_at + 2);
          const bool stronger = intensity > partner_intensity ||
                                (intensity == partner_intensity && raw < partner_raw);
          return_index = stronger ? 0 : 1;
        }
      }

      const int laser = laser_of(flags[static_cast<std::size_t>(b)], c);
      const LaserTable& l = lasers_[static_cast<std::size_t>(laser)];
      const double d = raw * distance_unit_m_ + l.dist_correction_m;
      if (d <= settings_.min_range_m || d > settings_.max_range_m) {
        ++r.out_of_range;
        continue;
      }
      const std::int32_t t_ns = timing_.offset_ns(r.dual, b, c);

      double cos_a = 0.0;
      double sin_a = 0.0;
      double azimuth_rad = 0.0;
      if (veloview) {
        // vtkVelodyneHDLReader::ProcessFiring, reproduced operation by operation so that the
        // rounding to 0.01 degree lands on the same side.
        double t = 0.0, t0 = 0.0, t1 = 0.0;
        if (model_ == Model::kHdl32e) {
          t = (b * 46.08) + (c * 1.152);
          t0 = (b * 46.08) + (0 * 1.152);
          t1 = ((b + 1) * 46.08) + (0 * 1.152);
        } else {
          const int firing = c / 16;
          t = (b * 110.592) + ((c % 16) * 2.304) + (firing * 55.296);
          t0 = (b * 110.592) + (0 * 2.304) + (0 * 55.296);
          t1 = ((b + 1) * 110.592) + (0 * 2.304) + (0 * 55.296);
        }
        const int adjust = veloview_round(veloview_diff * ((t - t0) / (t1 - t0)));
        const int azimuth = (block_azimuth + adjust) % 36000;
        azimuth_rad = ((azimuth / 100.0) - l.rot_deg) * kPi / 180.0;
        cos_a = std::cos(azimuth_rad);
        sin_a = std::sin(azimuth_rad);
      } else {
        const double delta = rate_rad_per_ns * static_cast<double>(t_ns - reference_ns);
        double cos_d = 0.0;
        double sin_d = 0.0;
        small_angle_cos_sin(delta, cos_d, sin_d);
        const double cos_t = cos_theta * cos_d - sin_theta * sin_d;  // theta + delta
        const double sin_t = sin_theta * cos_d + cos_theta * sin_d;
        cos_a = cos_t * l.cos_rot + sin_t * l.sin_rot;  // minus the rotational correction
        sin_a = sin_t * l.cos_rot - cos_t * l.sin_rot;
        azimuth_rad = theta + delta - l.rot_rad;
      }
      if (azimuth_rad < 0.0) azimuth_rad += 2.0 * kPi;
      if (azimuth_rad >= 2.0 * kPi) azimuth_rad -= 2.0 * kPi;

      const double xy = d * l.cos_vert - l.vert_offset_m * l.sin_vert;
      DecodedReturn& p = out[n++];
      p.x = static_cast<float>(xy * cos_a + l.horiz_offset_m * sin_a);
      p.y = static_cast<float>(-xy * sin_a + l.horiz_offset_m * cos_a);
      p.z = static_cast<float>(d * l.sin_vert + l.vert_offset_m * l.cos_vert);
      p.distance_m = static_cast<float>(d);
      p.azimuth_rad = static_cast<float>(azimuth_rad);
      p.t_offset_ns = t_ns + block_delay;
      p.laser = static_cast<std::uint16_t>(laser);
      p.ring = l.ring;
      p.intensity = intensity;
      p.return_index = return_index;
      p.block = static_cast<std::uint8_t>(b);
    }
  }
  r.block_begin[static_cast<std::size_t>(r.blocks_used)] = static_cast<std::uint16_t>(n);
  r.count = n;
  r.status = DataDecodeStatus::kOk;
  return r;
}

}  // namespace livod::drivers::velodyne
