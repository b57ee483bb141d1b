#pragma once
// Record-level pieces of the ROS bag 2.0 format shared by the reader and the writer.
//   file    = "#ROSBAG V2.0\n" record*
//   record  = u32 header_len, header, u32 data_len, data
//   header  = (u32 field_len, name '=' value)*, one field being op (u8)
// Numbers are little-endian; times are u32 sec + u32 nsec.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/rosbag/ros_serialization.hpp"

namespace livod::io::rosbag {

inline constexpr std::string_view kBagMagic = "#ROSBAG V2.0\n";

enum class BagOp : std::uint8_t {
  kMessageData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07,
};

// rosbag pads the bag header record's header + data to 4096 bytes so that it can be rewritten in
// place when the bag is closed.
inline constexpr std::size_t kBagHeaderPaddedLength = 4096;
// Index data and chunk info record version.
inline constexpr std::uint32_t kIndexVersion = 1;
// One index entry: time (u32 sec, u32 nsec) + u32 offset inside the uncompressed chunk.
inline constexpr std::size_t kIndexEntrySize = 12;
// One chunk info entry: u32 conn + u32 count.
inline constexpr std::size_t kChunkInfoEntrySize = 8;
// The smallest possible record: two lengths.
inline constexpr std::size_t kMinRecordSize = 8;

// A parsed record header (views into the caller's bytes and `source`, which must outlive it).
// parse() throws livod::FormatError with `source` and base_offset + the offset of the bad field.
class RecordHeader {
 public:
  static RecordHeader parse(std::span<const std::byte> bytes, std::string_view source,
                            std::uint64_t base_offset);

  [[nodiscard]] std::optional<std::span<const std::byte>> find(std::string_view name) const;
  [[nodiscard]] bool has(std::string_view name) const { return find(name).has_value(); }

  // Typed required fields: missing or wrongly sized fields throw livod::FormatError.
  [[nodiscard]] std::uint8_t op() const;
  [[nodiscard]] std::uint32_t u32(std::string_view name) const;
  [[nodiscard]] std::uint64_t u64(std::string_view name) const;
  [[nodiscard]] RosTime time(std::string_view name) const;
  [[nodiscard]] std::string string(std::string_view name) const;

  [[nodiscard]] std::uint64_t offset() const { return base_offset_; }

 private:
  [[nodiscard]] std::span<const std::byte> required(std::string_view name,
                                                    std::size_t exact_size) const;
  std::vector<std::pair<std::string_view, std::span<const std::byte>>> fields_;
  std::string_view source_;
  std::uint64_t base_offset_ = 0;
};

// Builds a record header (or a connection record's data, which has the same layout). Fields are
// written sorted by name, as rosbag's C++ writer does (it keeps them in a std::map), so the output
// does not depend on the order of add() calls.
class HeaderBuilder {
 public:
  HeaderBuilder& add(std::string_view name, std::span<const std::byte> value);
  HeaderBuilder& add(std::string_view name, std::string_view value);
  HeaderBuilder& add_op(BagOp op);
  HeaderBuilder& add_u32(std::string_view name, std::uint32_t value);
  HeaderBuilder& add_u64(std::string_view name, std::uint64_t value);
  HeaderBuilder& add_time(std::string_view name, RosTime value);

  // Total length of the fields (what header_len holds).
  [[nodiscard]] std::size_t size() const;
  // Appends u32 length + fields.
  void append_to(std::vector<std::byte>& out) const;

 private:
  std::vector<std::pair<std::string, std::vector<std::byte>>> fields_;
};

}  // namespace livod::io::rosbag
