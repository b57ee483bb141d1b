#pragma once
// Ouster UDP profiles: which fields a channel block of a lidar packet carries and where they sit.
//
// Bit positions are within the little-endian channel block (sensor-protocols.md §3.2-3.3, taken
// from ouster-sdk's parsing tables). A field is read as
//   ((le32(block + byte_offset) >> shift) & mask) << upshift
// where `upshift` restores the low bits the low-data-rate profiles drop (RNG15 range x8, NIR x16).

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "core/little_endian.hpp"

namespace livod::drivers::ouster {

enum class LidarProfile : std::uint8_t {
  kLegacy,
  kRng19Rfl8Sig16Nir16,
  kRng19Rfl8Sig16Nir16Dual,
  kRng15Rfl8Nir8,
  kRng15Rfl8Nir8Dual,
  kFusaRng15Rfl8Nir8Dual,
  kRng19Rfl8Sig16Nir16Zone16,
  kRng15Rfl8Nir8Zone16,
};

enum class ImuProfile : std::uint8_t { kLegacy, kAccel32Gyro32Nmea };

// Lidar/IMU packet header variant (FW >= 2.2 non-LEGACY profiles). FUSA packs packet_type into 8
// bits and widens frame_id to 32 bits.
enum class HeaderType : std::uint8_t { kStandard, kFusa };

enum class ChannelField : std::uint8_t {
  kRange,
  kRange2,
  kFlags,
  kFlags2,
  kReflectivity,
  kReflectivity2,
  kSignal,
  kSignal2,
  kNearIr,
  kWindow,
  kZoneMask,
  kRaw32Word1,
  kRaw32Word2,
  kRaw32Word3,
  kRaw32Word4,
};
inline constexpr std::size_t kChannelFieldCount = 15;

struct FieldLayout {
  std::uint8_t byte_offset = 0;
  std::uint8_t shift = 0;
  std::uint8_t upshift = 0;
  std::uint32_t mask = 0;  // 0 = the profile has no such field
  [[nodiscard]] constexpr bool present() const { return mask != 0; }
};

struct ProfileLayout {
  std::size_t channel_block_size = 0;  // bytes per pixel (per channel) in a column
  std::uint8_t returns = 1;            // 2 for the dual-return profiles
  std::array<FieldLayout, kChannelFieldCount> fields{};

  [[nodiscard]] constexpr const FieldLayout& field(ChannelField f) const {
    return fields[static_cast<std::size_t>(f)];
  }
  [[nodiscard]] constexpr bool has(ChannelField f) const { return field(f).present(); }
};

[[nodiscard]] const ProfileLayout& profile_layout(LidarProfile profile);

// Reads one field of one channel block. The caller guarantees 4 readable bytes at
// block + byte_offset: every field's load stays inside the packet because each channel block is
// followed by at least the 4-byte column status (LEGACY) or the 32-byte packet footer.
[[nodiscard]] inline std::uint32_t read_field(const std::byte* block, const FieldLayout& f) {
  const auto word = load_le<std::uint32_t>(block + f.byte_offset);
  return ((word >> f.shift) & f.mask) << f.upshift;
}

[[nodiscard]] std::optional<LidarProfile> lidar_profile_from_string(std::string_view name);
[[nodiscard]] std::optional<ImuProfile> imu_profile_from_string(std::string_view name);
[[nodiscard]] std::optional<HeaderType> header_type_from_string(std::string_view name);
[[nodiscard]] std::string_view to_string(LidarProfile profile);
[[nodiscard]] std::string_view to_string(ImuProfile profile);
[[nodiscard]] std::string_view to_string(ChannelField field);

}  // namespace livod::drivers::ouster
