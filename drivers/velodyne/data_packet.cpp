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

DataPacketResult DataPacketDecoder::decode(std::span<const std::byte> payload, double fallback_rate,
                                           std::span<DecodedReturn> out) const {
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

  // Mean rotation rate from the first block to the last block of a later firing sequence.
  const int last = r.blocks_used - 1;
  const std::int32_t span_ns =
      timing_.block_reference_ns(r.dual, last) - timing_.block_reference_ns(r.dual, 0);
  double rate = std::isfinite(fallback_rate) ? fallback_rate : 0.0;
  if (span_ns > 0) {
    const int diff =
        (36000 + r.block_azimuth[static_cast<std::size_t>(last)] - r.block_azimuth[0]) % 36000;
    const double measured = diff / static_cast<double>(span_ns);
    if (measured <= kMaxRateCentidegPerNs) {
      r.azimuth_rate = measured;
      rate = measured;
    }
  }
  const double rate_rad_per_ns = rate * kCentidegToRad;
  const bool veloview = settings_.azimuth == AzimuthInterpolation::kVeloView;
  const double veloview_diff = veloview ? veloview_azimuth_diff(r) : 0.0;

  std::size_t n = 0;
  for (int b = 0; b < r.blocks_used; ++b) {
    r.block_begin[static_cast<std::size_t>(b)] = static_cast<std::uint16_t>(n);
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
      p.t_offset_ns = t_ns;
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
