#include "drivers/imu/can_signal.hpp"

namespace livod::imu {
namespace {

constexpr int kBitsPerByte = 8;
constexpr int kMaxLength = 64;

// The position of the next bit of a field after `pos`: upwards for Intel signals (from the least
// significant bit), and for Motorola ones (from the most significant bit) down within a byte, then
// from bit 0 of a byte on to bit 7 of the next one.
int next_position(const CanBitField& f, int pos) {
  if (!f.big_endian) return pos + 1;
  return (pos % kBitsPerByte == 0) ? pos + 2 * kBitsPerByte - 1 : pos - 1;
}

// Position of the last bit of the field (its most significant bit for Intel, least significant
// for Motorola).
int last_position(const CanBitField& f) {
  int pos = f.start_bit;
  for (int k = 1; k < f.length; ++k) pos = next_position(f, pos);
  return pos;
}

}  // namespace

std::optional<int> bytes_needed(const CanBitField& f, int max_bytes) {
  const int total_bits = max_bytes * kBitsPerByte;
  if (f.length < 1 || f.length > kMaxLength || f.start_bit < 0 || f.start_bit >= total_bits) {
    return std::nullopt;
  }
  // Both orders reach their highest byte index with the last bit (Motorola signals continue into
  // the following bytes).
  const int last = last_position(f);
  if (last >= total_bits) return std::nullopt;
  return last / kBitsPerByte + 1;
}

std::string check_bit_field(const CanBitField& f, int max_bytes) {
  if (f.length < 1 || f.length > kMaxLength) return "length must be 1..64 bits";
  const int total_bits = max_bytes * kBitsPerByte;
  if (f.start_bit < 0 || f.start_bit >= total_bits) {
    return "start_bit must be 0.." + std::to_string(total_bits - 1);
  }
  if (!bytes_needed(f, max_bytes)) {
    return std::string(f.big_endian ? "the Motorola (big-endian) signal" : "the signal") +
           " runs past the " + std::to_string(total_bits) + " data bits of the frame";
  }
  return {};
}

std::int64_t extract_raw(std::span<const std::uint8_t> data, const CanBitField& f) {
  const int total_bits = static_cast<int>(data.size()) * kBitsPerByte;
  if (data.size() >= 8 && f.length < kMaxLength) {
    // Fast path for fields within the first 8 bytes: one 64-bit word, a shift and a mask. In the
    // little-endian word bit b is DBC bit b; in the big-endian word DBC bit b of byte b / 8 sits
    // at (b / 8) * 8 + 7 - b % 8 counted from the top.
    const std::uint64_t mask = (std::uint64_t{1} << f.length) - 1;
    std::uint64_t value = 0;
    bool fits = false;
    if (!f.big_endian && f.start_bit + f.length <= kMaxLength) {
      std::uint64_t le = 0;
      for (int i = 7; i >= 0; --i) le = (le << 8) | data[static_cast<std::size_t>(i)];
      value = (le >> f.start_bit) & mask;
      fits = true;
    } else if (f.big_endian) {
      const int msb_from_top =
          (f.start_bit / kBitsPerByte) * kBitsPerByte + 7 - f.start_bit % kBitsPerByte;
      if (msb_from_top + f.length <= kMaxLength) {
        std::uint64_t be = 0;
        for (int i = 0; i < 8; ++i) be = (be << 8) | data[static_cast<std::size_t>(i)];
        value = (be >> (kMaxLength - msb_from_top - f.length)) & mask;
        fits = true;
      }
    }
    if (fits) {
      if (f.is_signed && ((value >> (f.length - 1)) & 1U) != 0) value |= ~mask;
      return static_cast<std::int64_t>(value);
    }
  }
  std::uint64_t value = 0;
  int pos = f.start_bit;
  for (int k = 0; k < f.length; ++k, pos = next_position(f, pos)) {
    const std::uint64_t bit =
        (pos < 0 || pos >= total_bits)
            ? 0
            : (data[static_cast<std::size_t>(pos / kBitsPerByte)] >> (pos % kBitsPerByte)) & 1U;
    if (f.big_endian) {
      value = (value << 1) | bit;  // k counts from the most significant bit
    } else {
      value |= bit << k;
    }
  }
  if (f.is_signed && f.length < kMaxLength && ((value >> (f.length - 1)) & 1U) != 0) {
    value |= ~std::uint64_t{0} << f.length;
  }
  return static_cast<std::int64_t>(value);
}

void insert_raw(std::span<std::uint8_t> data, const CanBitField& f, std::int64_t raw) {
  const int total_bits = static_cast<int>(data.size()) * kBitsPerByte;
  const auto value = static_cast<std::uint64_t>(raw);
  int pos = f.start_bit;
  for (int k = 0; k < f.length; ++k, pos = next_position(f, pos)) {
    if (pos < 0 || pos >= total_bits) continue;
    const int value_bit = f.big_endian ? f.length - 1 - k : k;
    const auto mask = static_cast<std::uint8_t>(1U << (pos % kBitsPerByte));
    auto& byte = data[static_cast<std::size_t>(pos / kBitsPerByte)];
    byte = ((value >> value_bit) & 1U) != 0 ? static_cast<std::uint8_t>(byte | mask)
                                            : static_cast<std::uint8_t>(byte & ~mask);
  }
}

}  // namespace livod::imu
