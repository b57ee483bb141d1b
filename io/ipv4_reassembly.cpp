#include "io/ipv4_reassembly.hpp"

#include <algorithm>
#include <cstring>

namespace livod::io {

namespace {

// |a - b| without signed overflow, whatever clock values the caller passes.
std::uint64_t abs_difference(std::int64_t a, std::int64_t b) {
  const auto ua = static_cast<std::uint64_t>(a);
  const auto ub = static_cast<std::uint64_t>(b);
  return a >= b ? ua - ub : ub - ua;
}

// The IPv4 total length field is 16 bits, so no payload can reach 64 KiB.
constexpr std::size_t kMaxIpv4Payload = 65535;

}  // namespace

Ipv4Reassembler::Ipv4Reassembler(Ipv4ReassemblyLimits limits) : limits_(limits) {
  limits_.max_pending_sets = std::max<std::size_t>(1, limits_.max_pending_sets);
  limits_.max_datagram_bytes = std::min(limits_.max_datagram_bytes, kMaxIpv4Payload);
  limits_.timeout_ns = std::max<std::int64_t>(0, limits_.timeout_ns);
  slots_.resize(limits_.max_pending_sets);
}

bool Ipv4Reassembler::block_received(const Slot& slot, std::size_t block) {
  return ((slot.received[block / kBitsPerWord] >> (block % kBitsPerWord)) & 1U) != 0;
}

void Ipv4Reassembler::mark_block(Slot& slot, std::size_t block) {
  slot.received[block / kBitsPerWord] |= std::uint64_t{1} << (block % kBitsPerWord);
}

Ipv4Reassembler::Slot* Ipv4Reassembler::find(const Ipv4FragmentKey& key) {
  for (auto& slot : slots_) {
    if (slot.in_use && slot.key == key) return &slot;
  }
  return nullptr;
}

void Ipv4Reassembler::release(Slot& slot) {
  // The buffer keeps its capacity (and, until reused, its bytes: a completed datagram is handed
  // out as a view of it).
  slot.in_use = false;
}

Ipv4Reassembler::Slot& Ipv4Reassembler::allocate(const Ipv4FragmentKey& key, std::int64_t time_ns) {
  Slot* chosen = nullptr;
  for (auto& slot : slots_) {
    if (!slot.in_use) {
      chosen = &slot;
      break;
    }
  }
  if (chosen == nullptr) {
    chosen = &*std::min_element(slots_.begin(), slots_.end(), [](const Slot& a, const Slot& b) {
      return a.last_touch < b.last_touch;
    });
    ++stats_.evicted;
  }
  Slot& slot = *chosen;
  slot.in_use = true;
  slot.key = key;
  slot.first_time_ns = time_ns;
  slot.total_bytes = 0;
  slot.total_known = false;
  slot.max_end = 0;
  slot.blocks_received = 0;
  slot.received.fill(0);
  slot.buffer.clear();
  return slot;
}

void Ipv4Reassembler::expire(std::int64_t now_ns) {
  const auto timeout = static_cast<std::uint64_t>(limits_.timeout_ns);
  for (auto& slot : slots_) {
    if (slot.in_use && abs_difference(now_ns, slot.first_time_ns) > timeout) {
      release(slot);
      ++stats_.timed_out;
    }
  }
}

void Ipv4Reassembler::flush() {
  for (auto& slot : slots_) {
    if (slot.in_use) {
      release(slot);
      ++stats_.flushed;
    }
  }
}

std::size_t Ipv4Reassembler::pending_sets() const {
  return static_cast<std::size_t>(
      std::count_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.in_use; }));
}

Ipv4Reassembler::Result Ipv4Reassembler::add(const Ipv4Fragment& fragment, std::int64_t time_ns) {
  ++stats_.fragments;
  expire(time_ns);

  const std::size_t offset = fragment.offset_bytes;
  const std::size_t length = fragment.payload.size();
  const std::size_t end = offset + length;  // cannot overflow: offset < 2^32, length < 2^48
  const bool last = !fragment.more_fragments;
  // RFC 791: every fragment but the last carries a non-empty multiple of 8 bytes; an unfragmented
  // datagram (offset 0, MF clear) is not a fragment at all.
  const bool bad_shape = (!last && (length == 0 || length % kBlockBytes != 0)) ||
                         (last && offset == 0) || offset % kBlockBytes != 0;
  if (bad_shape || end > limits_.max_datagram_bytes) {
    ++stats_.invalid;
    return {Status::invalid, {}};
  }

  Slot* found = find(fragment.key);
  Slot& slot = found != nullptr ? *found : allocate(fragment.key, time_ns);
  slot.last_touch = ++touch_counter_;

  auto discard = [&] {
    release(slot);
    ++stats_.conflicts;
    return Result{Status::conflict, {}};
  };

  // Consistency with the total length announced by a last fragment (MF clear).
  if (slot.total_known) {
    if (end > slot.total_bytes || (last && end != slot.total_bytes)) return discard();
  } else if (last && slot.max_end > end) {
    return discard();
  }

  const std::size_t first_block = offset / kBlockBytes;
  const std::size_t end_block = (end + kBlockBytes - 1) / kBlockBytes;
  std::size_t already = 0;
  for (std::size_t b = first_block; b < end_block; ++b) {
    if (block_received(slot, b)) ++already;
  }
  const std::size_t new_blocks = end_block - first_block;
  if (already != 0 || (length == 0 && slot.total_known)) {
    const bool whole_repeat = already == new_blocks && (!last || slot.total_known) &&
                              (length == 0 || std::memcmp(slot.buffer.data() + offset,
                                                          fragment.payload.data(), length) == 0);
    if (!whole_repeat) return discard();
    ++stats_.duplicates;
    return {Status::duplicate, {}};
  }

  if (slot.buffer.size() < end) slot.buffer.resize(end);
  if (length != 0) std::memcpy(slot.buffer.data() + offset, fragment.payload.data(), length);
  for (std::size_t b = first_block; b < end_block; ++b) mark_block(slot, b);
  slot.blocks_received += new_blocks;
  slot.max_end = std::max(slot.max_end, static_cast<std::uint32_t>(end));
  if (last) {
    slot.total_known = true;
    slot.total_bytes = static_cast<std::uint32_t>(end);
  }

  if (slot.total_known &&
      slot.blocks_received == (slot.total_bytes + kBlockBytes - 1) / kBlockBytes) {
    release(slot);
    ++stats_.reassembled;
    return {Status::complete, std::span<const std::byte>(slot.buffer.data(), slot.total_bytes)};
  }
  return {Status::pending, {}};
}

}  // namespace livod::io
