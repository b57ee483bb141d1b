#pragma once
// livod::drivers::capture::PacketRing - a bounded single-producer/single-consumer queue of raw UDP
// payloads: how a capture thread hands received datagrams to the consumer that decodes them
// (DESIGN.md "Data flow"). Fixed-size slots (payload bytes up to a maximum chosen at run time,
// plus length, kernel receive time and destination port), all allocated by the constructor; a full
// ring drops the packet and counts an overrun, it never blocks.
//
// Layout: a core SpscRing of small descriptors (RawPacket: a span into the arena, the receive
// time, the port) and one byte arena of (capacity + 1) payload slots. The k-th successful push
// writes arena slot k mod (capacity + 1). This needs no synchronisation beyond the SpscRing's own:
// when the producer is about to write slot k mod (capacity + 1), its previous user was push
// k - capacity - 1, and the successful push k - 1 proves that item (k - 1) - capacity had been
// popped (otherwise capacity + 1 items would have been queued) and that the producer observed the
// pop through the ring's acquire load of the consumer index. So the consumer's reads of that slot
// happen-before the producer's new writes, and the descriptor's release publication makes the new
// bytes visible to the consumer. A push that fails leaves the counter unchanged; the bytes it wrote
// went to a slot no queued item uses.
//
// Threading contract: exactly one producer thread calls try_push; exactly one consumer thread
// calls front/pop; any thread may call capacity(), max_payload_bytes(), size_approx() and
// overruns(). Create the ring before starting the threads and destroy it after joining them.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "core/spsc_ring.hpp"
#include "core/time.hpp"

namespace livod::drivers::capture {

// One queued datagram as the consumer sees it. `payload` points into the ring's arena and stays
// valid until pop().
struct RawPacket {
  std::span<const std::byte> payload;
  HostTime rx;                 // kernel receive time (CLOCK_MONOTONIC)
  std::uint16_t dst_port = 0;  // the sensor port the datagram was sent to
  bool truncated = false;      // the datagram was longer than the slot (or the socket buffer)
};

class PacketRing {
 public:
  // Throws std::invalid_argument when capacity or max_payload_bytes is 0. Touches every arena page
  // here (zero fill) so that the capture thread never takes a page fault in steady state.
  PacketRing(std::size_t capacity, std::size_t max_payload_bytes);

  PacketRing(const PacketRing&) = delete;
  PacketRing& operator=(const PacketRing&) = delete;

  // ---- producer ------------------------------------------------------------------------------
  // Copies `payload` (cut to max_payload_bytes, which then sets `truncated`) into the ring.
  // Returns false, and counts an overrun, when the ring is full. Never blocks, never allocates.
  bool try_push(std::span<const std::byte> payload, HostTime rx, std::uint16_t dst_port,
                bool truncated = false);

  // ---- consumer ------------------------------------------------------------------------------
  // The oldest packet, or nullptr when the ring is empty. Valid until pop().
  [[nodiscard]] const RawPacket* front() { return ring_.front(); }
  // Removes the oldest packet. Precondition: front() returned non-null.
  void pop() { ring_.pop(); }

  // ---- any thread ----------------------------------------------------------------------------
  [[nodiscard]] std::size_t capacity() const { return ring_.capacity(); }
  [[nodiscard]] std::size_t max_payload_bytes() const { return max_payload_bytes_; }
  [[nodiscard]] std::size_t size_approx() const { return ring_.size_approx(); }
  // Packets dropped because the ring was full, since construction.
  [[nodiscard]] std::uint64_t overruns() const { return ring_.overruns(); }

 private:
  SpscRing<RawPacket> ring_;
  std::size_t max_payload_bytes_;
  std::size_t stride_;      // bytes between arena slots (max payload rounded up to a cache line)
  std::size_t slot_count_;  // capacity + 1
  std::unique_ptr<std::byte[]> arena_;
  // Producer-only: arena slot of the next push. On its own cache line, away from the consumer.
  alignas(kCacheLineBytes) std::size_t next_slot_ = 0;
};

}  // namespace livod::drivers::capture
