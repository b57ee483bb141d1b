#pragma once
// Bit-level CAN signals, DBC style: a signal is `length` bits of a frame's data starting at
// `start_bit`, Intel (little-endian) or Motorola (big-endian) bit numbering, unsigned or two's
// complement, physical value = raw * factor + offset.
//
// Bit numbering (as in DBC files): bit b is bit (b % 8) of data byte b / 8, bit 0 the least
// significant.
//   Intel:    start_bit is the signal's least significant bit; the signal occupies start_bit,
//             start_bit + 1, ... (crossing into the next byte upwards).
//   Motorola: start_bit is the signal's most significant bit; from there the bits run down within
//             a byte and continue at bit 7 of the next byte (the DBC "sawtooth").

#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace livod::imu {

struct CanBitField {
  int start_bit = 0;
  int length = 16;  // 1..64
  bool big_endian = false;
  bool is_signed = false;
};

// Highest data byte index the field touches + 1 (the frame length it needs), or nullopt when the
// field does not fit in `max_bytes` (8 classic, 64 FD) or has an invalid length.
[[nodiscard]] std::optional<int> bytes_needed(const CanBitField& field, int max_bytes = 8);

// Why a field is invalid for frames of `max_bytes`, or empty.
[[nodiscard]] std::string check_bit_field(const CanBitField& field, int max_bytes = 8);

// Raw value (sign-extended when is_signed). Precondition: bytes_needed(field) <= data.size().
[[nodiscard]] std::int64_t extract_raw(std::span<const std::uint8_t> data,
                                       const CanBitField& field);

// Writes the low `length` bits of `raw` into `data` (tests, simulator). Same precondition.
void insert_raw(std::span<std::uint8_t> data, const CanBitField& field, std::int64_t raw);

}  // namespace livod::imu
