#pragma once
// Hesai point cloud data packets: a pure decoder over bytes into a fixed-capacity packet (no
// allocation) and the matching encoder (simulator, tests). Layouts from Hesai's user manuals:
//
// PandarXT-32 (1080 bytes; all fields little-endian):
//   0   pre-header: 0xEE 0xFF, protocol major 6, minor 1, 2 reserved
//   6   header: laser num (32), block num (8), first block return, dis unit (mm), return number
//       (1 or 2), flags (bit 0: UDP sequence present, always set on the XT series)
//   12  body: 8 blocks x (azimuth u16 in 0.01 deg, 32 x (distance u16, reflectivity u8,
//       reserved u8))
//   1052 tail: 9 reserved, high temperature flag, return mode, motor speed u16 (RPM), date
//       (year - 1900, month, day, hour, minute, second), timestamp u32 (us), factory information
//   1076 UDP sequence u32
//
// Pandar40P (1262 bytes, 1266 with the UDP sequence on):
//   0   body: 10 blocks x (0xFFEE flag, azimuth u16, 40 x (distance u16 in 4 mm, reflectivity))
//   1240 additional information: 5 reserved, high temperature flag, 2 reserved, motor speed u16,
//       timestamp u32 (us), return mode, factory information, date (year - 2000, month, day,
//       hour, minute, second)
//   1262 UDP sequence u32 (when enabled)
//
// Return modes: 0x37 strongest, 0x38 last, 0x39 last + strongest (both models); the XT series
// adds 0x33 first, 0x3B last + first, 0x3C first + strongest. In dual return modes the blocks
// come in pairs with one azimuth (XT: odd block = last or first return per the header's first
// block return; 40P: odd block = last, even = strongest), the second block of the pair repeating
// the first block's distance when the two returns coincide.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "drivers/hesai/model.hpp"

namespace livod::drivers::hesai {

inline constexpr int kMaxChannels = 40;
inline constexpr int kMaxBlocks = 10;

// UDP payload sizes.
inline constexpr std::size_t kXt32PacketSize = 1080;
inline constexpr std::size_t kXt32PacketSizeNoSequence = 1076;
inline constexpr std::size_t kPandar40pPacketSize = 1262;
inline constexpr std::size_t kPandar40pPacketSizeWithSequence = 1266;
// GPS packets (port 10110) are 512 bytes.
inline constexpr std::size_t kGpsPacketSize = 512;

struct HesaiPacket {
  Model model = Model::kPandarXT32;
  int returns = 1;  // 1 single, 2 dual return
  std::uint8_t return_mode = 0x37;
  std::uint8_t first_block_return = 0;  // XT header byte (0 single, 1 last, 2 strongest)
  double distance_unit_m = 0.004;
  std::array<std::uint16_t, kMaxBlocks> azimuth{};  // 0.01 degree, 0 .. 35999
  // [block * kMaxChannels + channel]
  std::array<std::uint16_t, kMaxBlocks * kMaxChannels> distance{};  // raw, x distance_unit_m
  std::array<std::uint8_t, kMaxBlocks * kMaxChannels> reflectivity{};
  std::int64_t timestamp_ns = 0;  // UTC date + time + microseconds, ns since 1970
  std::optional<std::uint32_t> udp_sequence;
  std::uint16_t motor_rpm = 0;
  bool high_temperature = false;  // the sensor will shut down in 60 s
  std::uint8_t factory = 0x42;

  [[nodiscard]] std::uint16_t raw_distance(int block, int channel) const {
    return distance[static_cast<std::size_t>(block * kMaxChannels + channel)];
  }
  [[nodiscard]] std::uint8_t raw_reflectivity(int block, int channel) const {
    return reflectivity[static_cast<std::size_t>(block * kMaxChannels + channel)];
  }
};

enum class PacketError : std::uint8_t {
  kNone,
  kWrongSize,      // no packet of this model has this length
  kBadHeader,      // start of packet, protocol version, block flags or flags not the model's
  kWrongModel,     // laser or block count of another model
  kBadAzimuth,     // an azimuth of 360 degrees or more
  kBadReturnMode,  // unknown return mode, or one inconsistent with the return number
  kBadTime,        // impossible date or microseconds
};
inline constexpr std::size_t kPacketErrorKinds = 7;
[[nodiscard]] const char* to_string(PacketError e);

// Decodes one UDP payload of `model`. Anything that is not exactly that model's point cloud
// packet is an error and leaves `out` unusable. Only the model's blocks and channels are written:
// entries beyond them keep what an earlier packet left.
[[nodiscard]] PacketError decode_packet(Model model, std::span<const std::byte> payload,
                                        HesaiPacket& out);

// Encodes `packet` as `packet.model` sends it (UDP sequence written when present; a Pandar40P
// packet without one is 1262 bytes). Distances and reflectivities beyond the model's blocks and
// channels are ignored.
[[nodiscard]] std::vector<std::byte> encode_packet(const HesaiPacket& packet);

[[nodiscard]] bool is_dual_return(std::uint8_t return_mode);

}  // namespace livod::drivers::hesai
