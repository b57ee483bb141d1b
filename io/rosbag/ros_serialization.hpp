#pragma once
// ROS1 wire serialization primitives: little-endian fixed-size values, strings and variable arrays
// as a u32 length/count followed by the bytes/items, fixed arrays without a count, time as u32 sec
// + u32 nsec. RosReader bounds-checks every read against the message size and throws
// livod::FormatError (source = message type, offset = byte offset inside the message) on short
// or inconsistent input, so a deserializer built on it can never read out of bounds or allocate
// from a bogus length.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/error.hpp"

namespace livod::io::rosbag {

// ROS time (and the bag record time): unsigned seconds + nanoseconds since the epoch.
struct RosTime {
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;

  [[nodiscard]] constexpr std::int64_t to_ns() const {
    return static_cast<std::int64_t>(sec) * 1'000'000'000 + static_cast<std::int64_t>(nsec);
  }
  // Throws livod::Error when ns is negative or beyond the u32 seconds range.
  static RosTime from_ns(std::int64_t ns);

  friend constexpr bool operator==(const RosTime&, const RosTime&) = default;
};

namespace detail {

template <class T>
concept WireScalar = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;

// Unsigned integer of the same size as T (the wire image of T).
template <class T>
using WireBits = std::conditional_t<
    sizeof(T) == 1, std::uint8_t,
    std::conditional_t<sizeof(T) == 2, std::uint16_t,
                       std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;

template <WireScalar T>
T load_le(const std::byte* p) {
  WireBits<T> bits = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    bits |= static_cast<WireBits<T>>(static_cast<WireBits<T>>(p[i]) << (8 * i));
  }
  return std::bit_cast<T>(bits);
}

template <WireScalar T>
void store_le(T value, std::byte* p) {
  const auto bits = std::bit_cast<WireBits<T>>(value);
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    p[i] = static_cast<std::byte>((bits >> (8 * i)) & 0xFFu);
  }
}

}  // namespace detail

class RosReader {
 public:
  // `what` names the message type in error messages; it must outlive the reader.
  RosReader(std::span<const std::byte> bytes, std::string_view what) : bytes_(bytes), what_(what) {}

  template <detail::WireScalar T>
  T read() {
    require(sizeof(T), "value");
    const T v = detail::load_le<T>(bytes_.data() + pos_);
    pos_ += sizeof(T);
    return v;
  }
  bool read_bool() { return read<std::uint8_t>() != 0; }
  RosTime read_time() {
    RosTime t;
    t.sec = read<std::uint32_t>();
    t.nsec = read<std::uint32_t>();
    return t;
  }
  // u32 length + bytes.
  std::string read_string() {
    const std::uint32_t n = read_count(1, "string");
    if (n == 0) return {};
    std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  // u32 count + bytes, as a view into the message (no copy).
  std::span<const std::byte> read_byte_array() {
    const std::uint32_t n = read_count(1, "uint8[]");
    return read_bytes(n);
  }
  std::span<const std::byte> read_bytes(std::size_t n) {
    require(n, "bytes");
    auto s = bytes_.subspan(pos_, n);
    pos_ += n;
    return s;
  }
  // u32 element count of a variable array whose elements take at least `min_element_size` bytes;
  // the count is checked against the remaining bytes before anyone allocates for it.
  std::uint32_t read_count(std::size_t min_element_size, std::string_view what_array) {
    const std::size_t at = pos_;
    const auto n = read<std::uint32_t>();
    if (min_element_size != 0 && n > remaining() / min_element_size) {
      pos_ = at;
      fail("array '" + std::string(what_array) + "' declares " + std::to_string(n) +
           " elements of >= " + std::to_string(min_element_size) + " bytes but only " +
           std::to_string(remaining() - 4) + " bytes remain");
    }
    return n;
  }

  [[nodiscard]] std::size_t offset() const { return pos_; }
  [[nodiscard]] std::size_t remaining() const { return bytes_.size() - pos_; }

  // A message must be consumed exactly: trailing bytes mean the bytes are not this type.
  void expect_end() const {
    if (pos_ != bytes_.size()) {
      fail(std::to_string(bytes_.size() - pos_) + " trailing bytes after the message");
    }
  }

  [[noreturn]] void fail(const std::string& message) const {
    throw FormatError(std::string(what_) + " message", pos_, message);
  }

 private:
  void require(std::size_t n, std::string_view what_value) const {
    if (n > remaining()) {
      fail("truncated: " + std::string(what_value) + " needs " + std::to_string(n) +
           " bytes, only " + std::to_string(remaining()) + " remain");
    }
  }

  std::span<const std::byte> bytes_;
  std::size_t pos_ = 0;
  std::string_view what_;
};

// Appends ROS1-serialized values to a byte vector.
class RosWriter {
 public:
  explicit RosWriter(std::vector<std::byte>& out) : out_(out) {}

  template <detail::WireScalar T>
  void write(T value) {
    const std::size_t at = out_.size();
    out_.resize(at + sizeof(T));
    detail::store_le<T>(value, out_.data() + at);
  }
  void write_bool(bool value) { write<std::uint8_t>(value ? 1 : 0); }
  void write_time(RosTime t) {
    write(t.sec);
    write(t.nsec);
  }
  // Lengths and counts are u32 on the wire; larger inputs throw livod::Error.
  void write_count(std::size_t n);
  void write_string(std::string_view s) {
    write_count(s.size());
    write_bytes(std::as_bytes(std::span(s.data(), s.size())));
  }
  void write_byte_array(std::span<const std::byte> bytes) {
    write_count(bytes.size());
    write_bytes(bytes);
  }
  void write_bytes(std::span<const std::byte> bytes) {
    out_.insert(out_.end(), bytes.begin(), bytes.end());
  }

 private:
  std::vector<std::byte>& out_;
};

}  // namespace livod::io::rosbag
