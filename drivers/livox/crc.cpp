#include "drivers/livox/crc.hpp"

#include <array>

namespace livod::livox {
namespace {

// Reflected (LSB-first) table for a reflected polynomial.
template <class T>
constexpr std::array<T, 256> reflected_table(T poly) {
  std::array<T, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    T c = static_cast<T>(i);
    for (int k = 0; k < 8; ++k)
      c = (c & 1U) ? static_cast<T>((c >> 1) ^ poly) : static_cast<T>(c >> 1);
    table[i] = c;
  }
  return table;
}

// MSB-first table for CRC-16/CCITT.
constexpr std::array<std::uint16_t, 256> msb_table16(std::uint16_t poly) {
  std::array<std::uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    auto c = static_cast<std::uint16_t>(i << 8);
    for (int k = 0; k < 8; ++k) {
      c = (c & 0x8000U) ? static_cast<std::uint16_t>((c << 1) ^ poly)
                        : static_cast<std::uint16_t>(c << 1);
    }
    table[i] = c;
  }
  return table;
}

constexpr auto kTable16Reflected = reflected_table<std::uint16_t>(0x8408);
constexpr auto kTable32Reflected = reflected_table<std::uint32_t>(0xEDB88320U);
constexpr auto kTable16Ccitt = msb_table16(0x1021);

std::uint16_t crc16_reflected(std::span<const std::byte> data, std::uint16_t reg) {
  for (const std::byte b : data) {
    reg = static_cast<std::uint16_t>(
        (reg >> 8) ^ kTable16Reflected[(reg ^ static_cast<std::uint8_t>(b)) & 0xFFU]);
  }
  return reg;
}

std::uint32_t crc32_reflected(std::span<const std::byte> data, std::uint32_t reg) {
  for (const std::byte b : data) {
    reg = (reg >> 8) ^ kTable32Reflected[(reg ^ static_cast<std::uint8_t>(b)) & 0xFFU];
  }
  return reg;
}

}  // namespace

std::uint16_t crc16_sdk1(std::span<const std::byte> data) {
  return crc16_reflected(data, 0x4C49);
}

std::uint32_t crc32_sdk1(std::span<const std::byte> data) {
  constexpr std::uint32_t kSeed = 0x564F580AU;
  return crc32_reflected(data, kSeed ^ 0xFFFFFFFFU) ^ 0xFFFFFFFFU;
}

std::uint16_t crc16_ccitt_false(std::span<const std::byte> data) {
  std::uint16_t reg = 0xFFFF;
  for (const std::byte b : data) {
    reg = static_cast<std::uint16_t>(
        (reg << 8) ^ kTable16Ccitt[((reg >> 8) ^ static_cast<std::uint8_t>(b)) & 0xFFU]);
  }
  return reg;
}

std::uint32_t crc32_standard(std::span<const std::byte> data) {
  return crc32_reflected(data, 0xFFFFFFFFU) ^ 0xFFFFFFFFU;
}

}  // namespace livod::livox
