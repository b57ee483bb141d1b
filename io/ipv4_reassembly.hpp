#pragma once
// IPv4 fragment reassembly (RFC 791) with a bounded table, for capture readers.
//
// Sets are keyed by (source, destination, identification, protocol). Memory is bounded: at most
// `max_pending_sets` sets exist at once, each at most `max_datagram_bytes` long; when the table is
// full the least recently touched set is evicted, and sets older than `timeout_ns` (in the
// caller's clock, e.g. pcap record time) expire. Slot buffers keep their capacity, so a steady
// stream of fragments does not allocate once every slot has grown to the datagram size in use.
//
// Overlaps are handled like modern stacks (RFC 5722 for IPv6, Linux for IPv4 since 4.19): a
// fragment that repeats bytes already received with identical content is a harmless duplicate
// (capture taps and retransmitting switches produce those) and is ignored; any other overlap, or a
// second "last fragment" that disagrees on the total length, discards the whole set, because
// choosing either version would let crafted traffic decide what the reader sees.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace livod::io {

struct Ipv4FragmentKey {
  std::uint32_t src_ip = 0;  // host byte order
  std::uint32_t dst_ip = 0;  // host byte order
  std::uint16_t id = 0;      // IPv4 identification field
  std::uint8_t protocol = 0;
  friend bool operator==(const Ipv4FragmentKey&, const Ipv4FragmentKey&) = default;
};

// One fragment: the IPv4 payload bytes it carries and where they go in the original payload.
struct Ipv4Fragment {
  Ipv4FragmentKey key;
  std::uint32_t offset_bytes = 0;  // fragment offset field x 8
  bool more_fragments = false;     // MF flag
  std::span<const std::byte> payload;
};

struct Ipv4ReassemblyLimits {
  std::size_t max_pending_sets = 64;
  // Largest IPv4 payload (without the IP header) accepted. 65515 = 65535 minus the minimum IPv4
  // header: anything longer could not have been sent (the "ping of death").
  std::size_t max_datagram_bytes = 65515;
  std::int64_t timeout_ns = 1'000'000'000;  // sets not completed within this are dropped
};

struct Ipv4ReassemblyStats {
  std::uint64_t fragments = 0;    // fragments offered to add()
  std::uint64_t reassembled = 0;  // sets completed
  std::uint64_t duplicates = 0;   // fragments repeating already received bytes (ignored)
  std::uint64_t invalid = 0;      // fragments rejected on their own (length rules, too large)
  std::uint64_t conflicts = 0;    // sets discarded because fragments contradicted each other
  std::uint64_t timed_out = 0;    // sets dropped after timeout_ns
  std::uint64_t evicted = 0;      // sets dropped because the table was full
  std::uint64_t flushed = 0;      // sets dropped by flush() (e.g. at the end of a capture)
  [[nodiscard]] std::uint64_t incomplete() const { return timed_out + evicted + flushed; }
};

class Ipv4Reassembler {
 public:
  enum class Status {
    pending,    // stored, the set is not complete yet
    complete,   // this fragment completed the set: `datagram` is the whole IPv4 payload
    duplicate,  // repeated bytes, ignored
    invalid,    // fragment rejected (counted in stats().invalid)
    conflict,   // the fragment contradicted its set; the set was discarded
  };
  struct Result {
    Status status = Status::pending;
    // The reassembled IPv4 payload when status == complete; valid until the next call of any
    // non-const member.
    std::span<const std::byte> datagram;
  };

  explicit Ipv4Reassembler(Ipv4ReassemblyLimits limits = {});

  // Adds one fragment received at `time_ns` (any monotonic-ish clock; only differences matter).
  // Expired sets are dropped first.
  Result add(const Ipv4Fragment& fragment, std::int64_t time_ns);

  // Drops sets whose first fragment is more than timeout_ns away from now_ns (either direction,
  // so that a capture whose clock jumps back cannot pin sets forever).
  void expire(std::int64_t now_ns);

  // Drops every pending set, counting each in stats().flushed.
  void flush();

  [[nodiscard]] std::size_t pending_sets() const;
  [[nodiscard]] const Ipv4ReassemblyStats& stats() const { return stats_; }
  [[nodiscard]] const Ipv4ReassemblyLimits& limits() const { return limits_; }

 private:
  // Coverage is tracked in 8-byte blocks, the unit of the fragment offset field.
  static constexpr std::size_t kBlockBytes = 8;
  static constexpr std::size_t kMaxBlocks = 65536 / kBlockBytes;
  static constexpr std::size_t kBitsPerWord = 64;

  struct Slot {
    bool in_use = false;
    Ipv4FragmentKey key;
    std::int64_t first_time_ns = 0;
    std::uint64_t last_touch = 0;   // arrival sequence number, for least-recently-used eviction
    std::uint32_t total_bytes = 0;  // known once the last fragment (MF = 0) arrived
    bool total_known = false;
    std::uint32_t max_end = 0;  // furthest byte received so far
    std::size_t blocks_received = 0;
    std::array<std::uint64_t, kMaxBlocks / kBitsPerWord> received{};  // one bit per block
    std::vector<std::byte> buffer;
  };

  Slot* find(const Ipv4FragmentKey& key);
  Slot& allocate(const Ipv4FragmentKey& key, std::int64_t time_ns);
  static void release(Slot& slot);
  static bool block_received(const Slot& slot, std::size_t block);
  static void mark_block(Slot& slot, std::size_t block);

  Ipv4ReassemblyLimits limits_;
  std::vector<Slot> slots_;
  std::uint64_t touch_counter_ = 0;
  Ipv4ReassemblyStats stats_;
};

}  // namespace livod::io
