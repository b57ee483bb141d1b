#pragma once
// The CRC variants of the Livox protocols (sensor-protocols.md 1.2, 2.2, Appendix A).
//   SDK1 control frames: CRC-16 MCRF4XX with register preset 0x4C49 (check 0xAB4E) and a
//     reflected CRC-32 whose register starts at seed 0x564F580A ^ 0xFFFFFFFF (check 0xB08DB5B1).
//   SDK2 control frames: CRC-16/CCITT-FALSE (check 0x29B1) and the standard CRC-32 (0xCBF43926).
// Bitwise implementations over a 256-entry table built at compile time.

#include <cstddef>
#include <cstdint>
#include <span>

namespace livod::livox {

std::uint16_t crc16_sdk1(std::span<const std::byte> data);
std::uint32_t crc32_sdk1(std::span<const std::byte> data);
std::uint16_t crc16_ccitt_false(std::span<const std::byte> data);
std::uint32_t crc32_standard(std::span<const std::byte> data);

}  // namespace livod::livox
