#pragma once
// A validated view of one Ouster lidar packet. parse() checks the length, the packet type, the
// CRC (when the format says there is one) and the column measurement ids; after that the
// accessors read fields straight from the caller's bytes without further checks. Nothing is
// copied or allocated.

#include <cstdint>
#include <span>

#include "core/little_endian.hpp"
#include "drivers/ouster/packet_format.hpp"
#include "drivers/ouster/profile.hpp"

namespace livod::drivers::ouster {

class LidarPacket {
 public:
  // On success fills `out` (a view into `bytes`, valid while `bytes` and `format` live).
  [[nodiscard]] static PacketError parse(std::span<const std::byte> bytes,
                                         const PacketFormat& format, LidarPacket& out);

  // Packet header. LEGACY packets have none: frame_id comes from column 0, the rest is zero.
  [[nodiscard]] const PacketHeader& header() const { return header_; }
  [[nodiscard]] const PacketFormat& format() const { return *format_; }
  [[nodiscard]] std::uint32_t columns() const { return format_->columns_per_packet; }

  [[nodiscard]] std::uint64_t column_timestamp_ns(std::uint32_t col) const {
    return load_le<std::uint64_t>(column(col));
  }
  [[nodiscard]] std::uint16_t measurement_id(std::uint32_t col) const {
    return load_le<std::uint16_t>(column(col) + 8);
  }
  // LEGACY: the 32-bit column footer (0xFFFFFFFF valid); otherwise the 16-bit header status.
  [[nodiscard]] std::uint32_t column_status(std::uint32_t col) const {
    const std::byte* c = column(col);
    return format_->legacy_lidar() ? load_le<std::uint32_t>(c + format_->column_size - 4)
                                   : load_le<std::uint16_t>(c + 10);
  }
  [[nodiscard]] bool column_valid(std::uint32_t col) const {
    return (column_status(col) & 1U) != 0;
  }
  // Per-column frame id and encoder count exist only in LEGACY packets (0 otherwise).
  [[nodiscard]] std::uint16_t column_frame_id(std::uint32_t col) const {
    return format_->legacy_lidar() ? load_le<std::uint16_t>(column(col) + 10) : 0;
  }
  [[nodiscard]] std::uint32_t column_encoder_count(std::uint32_t col) const {
    return format_->legacy_lidar() ? load_le<std::uint32_t>(column(col) + 12) : 0;
  }

  // Start of the channel block of row `px` in column `col`.
  [[nodiscard]] const std::byte* channel_block(std::uint32_t col, std::uint32_t px) const {
    return column(col) + format_->column_header_size + px * format_->layout->channel_block_size;
  }
  // One field of one pixel; 0 when the profile has no such field.
  [[nodiscard]] std::uint32_t field(std::uint32_t col, std::uint32_t px, ChannelField f) const {
    const FieldLayout& layout = format_->layout->field(f);
    return layout.present() ? read_field(channel_block(col, px), layout) : 0;
  }

 private:
  [[nodiscard]] const std::byte* column(std::uint32_t col) const {
    return data_ + format_->packet_header_size + col * format_->column_size;
  }

  const std::byte* data_ = nullptr;
  const PacketFormat* format_ = nullptr;
  PacketHeader header_;
};

}  // namespace livod::drivers::ouster
