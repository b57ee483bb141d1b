#include "drivers/capture/packet_ring.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <new>
#include <stdexcept>

namespace livod::drivers::capture {
namespace {

std::size_t checked_payload_bytes(std::size_t max_payload_bytes) {
  if (max_payload_bytes == 0) {
    throw std::invalid_argument("PacketRing: max_payload_bytes must be at least 1");
  }
  return max_payload_bytes;
}

std::size_t round_up_to_line(std::size_t n) {
  if (n > SIZE_MAX - kCacheLineBytes) throw std::bad_array_new_length();
  return (n + kCacheLineBytes - 1) / kCacheLineBytes * kCacheLineBytes;
}

std::size_t arena_bytes(std::size_t slots, std::size_t stride) {
  if (stride > SIZE_MAX / slots) throw std::bad_array_new_length();
  return slots * stride;
}

}  // namespace

PacketRing::PacketRing(std::size_t capacity, std::size_t max_payload_bytes)
    : ring_(capacity),
      max_payload_bytes_(checked_payload_bytes(max_payload_bytes)),
      stride_(round_up_to_line(max_payload_bytes)),
      slot_count_(capacity + 1),
      // make_unique value-initialises: the zero fill commits every page now, not in the capture
      // thread.
      arena_(std::make_unique<std::byte[]>(arena_bytes(slot_count_, stride_))) {}

bool PacketRing::try_push(std::span<const std::byte> payload, HostTime rx, std::uint16_t dst_port,
                          bool truncated) {
  const std::size_t length = std::min(payload.size(), max_payload_bytes_);
  std::byte* const slot = arena_.get() + next_slot_ * stride_;
  // Safe before knowing whether the push succeeds: see the header (slot reuse argument).
  if (length > 0) std::memcpy(slot, payload.data(), length);
  const RawPacket packet{std::span<const std::byte>(slot, length), rx, dst_port,
                         truncated || length < payload.size()};
  if (!ring_.try_push(packet)) return false;
  next_slot_ = next_slot_ + 1 == slot_count_ ? 0 : next_slot_ + 1;
  return true;
}

}  // namespace livod::drivers::capture
