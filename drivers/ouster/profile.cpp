#include "drivers/ouster/profile.hpp"

#include <utility>

namespace livod::drivers::ouster {
namespace {

// A field `bits` wide starting at `bit_start` of the channel block.
struct FieldSpec {
  ChannelField field;
  std::uint32_t bit_start;
  std::uint32_t bits;
  std::uint8_t upshift = 0;
};

template <std::size_t N>
constexpr ProfileLayout make_layout(std::size_t block_size, std::uint8_t returns,
                                    const std::array<FieldSpec, N>& specs) {
  ProfileLayout layout;
  layout.channel_block_size = block_size;
  layout.returns = returns;
  for (const FieldSpec& s : specs) {
    FieldLayout& f = layout.fields[static_cast<std::size_t>(s.field)];
    f.byte_offset = static_cast<std::uint8_t>(s.bit_start / 8);
    f.shift = static_cast<std::uint8_t>(s.bit_start % 8);
    f.upshift = s.upshift;
    f.mask = s.bits >= 32 ? 0xFFFFFFFFu : ((1u << s.bits) - 1u);
  }
  return layout;
}

using F = ChannelField;

// LEGACY REFLECTIVITY is the 16-bit word at bits 32-47: firmware up to 2.0 fills all 16 bits
// (values above 255 are common), 2.1 and later write 8-bit calibrated reflectivity and leave the
// high byte 0. Reading only 8 bits wrapped the old firmware's values modulo 256 (issue 13).
constexpr ProfileLayout kLegacyLayout = make_layout<8>(12, 1,
                                                       {{{F::kRange, 0, 20},
                                                         {F::kFlags, 28, 4},
                                                         {F::kReflectivity, 32, 16},
                                                         {F::kSignal, 48, 16},
                                                         {F::kNearIr, 64, 16},
                                                         {F::kRaw32Word1, 0, 32},
                                                         {F::kRaw32Word2, 32, 32},
                                                         {F::kRaw32Word3, 64, 32}}});

constexpr ProfileLayout kSingleLayout = make_layout<9>(12, 1,
                                                       {{{F::kRange, 0, 19},
                                                         {F::kFlags, 19, 5},
                                                         {F::kReflectivity, 32, 8},
                                                         {F::kSignal, 48, 16},
                                                         {F::kNearIr, 64, 16},
                                                         {F::kWindow, 88, 8},
                                                         {F::kRaw32Word1, 0, 32},
                                                         {F::kRaw32Word2, 32, 32},
                                                         {F::kRaw32Word3, 64, 32}}});

constexpr ProfileLayout kDualLayout = make_layout<14>(16, 2,
                                                      {{{F::kRange, 0, 19},
                                                        {F::kFlags, 19, 5},
                                                        {F::kReflectivity, 24, 8},
                                                        {F::kRange2, 32, 19},
                                                        {F::kFlags2, 51, 5},
                                                        {F::kReflectivity2, 56, 8},
                                                        {F::kSignal, 64, 16},
                                                        {F::kSignal2, 80, 16},
                                                        {F::kNearIr, 96, 16},
                                                        {F::kWindow, 120, 8},
                                                        {F::kRaw32Word1, 0, 32},
                                                        {F::kRaw32Word2, 32, 32},
                                                        {F::kRaw32Word3, 64, 32},
                                                        {F::kRaw32Word4, 96, 32}}});

constexpr ProfileLayout kLowDataRateLayout = make_layout<5>(4, 1,
                                                            {{{F::kRange, 0, 15, 3},
                                                              {F::kFlags, 15, 1},
                                                              {F::kReflectivity, 16, 8},
                                                              {F::kNearIr, 24, 8, 4},
                                                              {F::kRaw32Word1, 0, 32}}});

// RNG15_RFL8_NIR8_DUAL and FUSA_RNG15_RFL8_NIR8_DUAL share the channel block.
constexpr ProfileLayout kLowDataRateDualLayout = make_layout<10>(8, 2,
                                                                 {{{F::kRange, 0, 15, 3},
                                                                   {F::kFlags, 15, 1},
                                                                   {F::kReflectivity, 16, 8},
                                                                   {F::kNearIr, 24, 8, 4},
                                                                   {F::kRange2, 32, 15, 3},
                                                                   {F::kFlags2, 47, 1},
                                                                   {F::kReflectivity2, 48, 8},
                                                                   {F::kWindow, 56, 8},
                                                                   {F::kRaw32Word1, 0, 32},
                                                                   {F::kRaw32Word2, 32, 32}}});

constexpr ProfileLayout kSingleZoneLayout = make_layout<9>(12, 1,
                                                           {{{F::kRange, 0, 19},
                                                             {F::kFlags, 19, 5},
                                                             {F::kReflectivity, 32, 8},
                                                             {F::kSignal, 48, 16},
                                                             {F::kNearIr, 64, 16},
                                                             {F::kZoneMask, 80, 16},
                                                             {F::kRaw32Word1, 0, 32},
                                                             {F::kRaw32Word2, 32, 32},
                                                             {F::kRaw32Word3, 64, 32}}});

constexpr ProfileLayout kLowDataRateZoneLayout = make_layout<7>(8, 1,
                                                                {{{F::kRange, 0, 15, 3},
                                                                  {F::kFlags, 15, 1},
                                                                  {F::kReflectivity, 16, 8},
                                                                  {F::kNearIr, 24, 8, 4},
                                                                  {F::kZoneMask, 32, 16},
                                                                  {F::kRaw32Word1, 0, 32},
                                                                  {F::kRaw32Word2, 32, 32}}});

constexpr std::array<std::pair<LidarProfile, std::string_view>, 8> kLidarProfileNames{{
    {LidarProfile::kLegacy, "LEGACY"},
    {LidarProfile::kRng19Rfl8Sig16Nir16, "RNG19_RFL8_SIG16_NIR16"},
    {LidarProfile::kRng19Rfl8Sig16Nir16Dual, "RNG19_RFL8_SIG16_NIR16_DUAL"},
    {LidarProfile::kRng15Rfl8Nir8, "RNG15_RFL8_NIR8"},
    {LidarProfile::kRng15Rfl8Nir8Dual, "RNG15_RFL8_NIR8_DUAL"},
    {LidarProfile::kFusaRng15Rfl8Nir8Dual, "FUSA_RNG15_RFL8_NIR8_DUAL"},
    {LidarProfile::kRng19Rfl8Sig16Nir16Zone16, "RNG19_RFL8_SIG16_NIR16_ZONE16"},
    {LidarProfile::kRng15Rfl8Nir8Zone16, "RNG15_RFL8_NIR8_ZONE16"},
}};

constexpr std::array<std::string_view, kChannelFieldCount> kFieldNames{
    "RANGE",         "RANGE2",      "FLAGS",       "FLAGS2",      "REFLECTIVITY",
    "REFLECTIVITY2", "SIGNAL",      "SIGNAL2",     "NEAR_IR",     "WINDOW",
    "ZONE_MASK",     "RAW32_WORD1", "RAW32_WORD2", "RAW32_WORD3", "RAW32_WORD4"};

}  // namespace

const ProfileLayout& profile_layout(LidarProfile profile) {
  switch (profile) {
    case LidarProfile::kLegacy:
      return kLegacyLayout;
    case LidarProfile::kRng19Rfl8Sig16Nir16:
      return kSingleLayout;
    case LidarProfile::kRng19Rfl8Sig16Nir16Dual:
      return kDualLayout;
    case LidarProfile::kRng15Rfl8Nir8:
      return kLowDataRateLayout;
    case LidarProfile::kRng15Rfl8Nir8Dual:
    case LidarProfile::kFusaRng15Rfl8Nir8Dual:
      return kLowDataRateDualLayout;
    case LidarProfile::kRng19Rfl8Sig16Nir16Zone16:
      return kSingleZoneLayout;
    case LidarProfile::kRng15Rfl8Nir8Zone16:
      return kLowDataRateZoneLayout;
  }
  return kLegacyLayout;
}

std::optional<LidarProfile> lidar_profile_from_string(std::string_view name) {
  for (const auto& [profile, text] : kLidarProfileNames) {
    if (text == name) return profile;
  }
  return std::nullopt;
}

std::optional<ImuProfile> imu_profile_from_string(std::string_view name) {
  if (name == "LEGACY") return ImuProfile::kLegacy;
  if (name == "ACCEL32_GYRO32_NMEA") return ImuProfile::kAccel32Gyro32Nmea;
  return std::nullopt;
}

std::optional<HeaderType> header_type_from_string(std::string_view name) {
  if (name == "STANDARD") return HeaderType::kStandard;
  if (name == "FUSA") return HeaderType::kFusa;
  return std::nullopt;
}

std::string_view to_string(LidarProfile profile) {
  for (const auto& [p, text] : kLidarProfileNames) {
    if (p == profile) return text;
  }
  return "UNKNOWN";
}

std::string_view to_string(ImuProfile profile) {
  return profile == ImuProfile::kLegacy ? "LEGACY" : "ACCEL32_GYRO32_NMEA";
}

std::string_view to_string(ChannelField field) {
  return kFieldNames[static_cast<std::size_t>(field)];
}

}  // namespace livod::drivers::ouster
