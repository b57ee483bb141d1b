// libFuzzer target: Ipv4Reassembler driven by a fuzzer-chosen sequence of fragments of four
// datagrams. Fragment bytes come from a per-datagram pattern unless the fuzzer marks a fragment
// "corrupt"; a datagram completed from uncorrupted fragments must equal the pattern exactly. A
// small table and timeout make eviction and expiry reachable.
//
// Input: 5 bytes per fragment:
//   [0] bits 0-1 datagram, bit 2 MF, bit 3 corrupt, bits 4-7 clock step (15 = jump back 5000)
//   [1..2] offset in 8-byte units (13 bits, big-endian)   [3..4] length in bytes (11 bits)
// An input byte 0xFF in position [0] flushes the table instead.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "io/ipv4_reassembly.hpp"

namespace {

std::byte pattern(unsigned datagram, std::size_t position) {
  return static_cast<std::byte>((position * 31 + datagram * 101 + (position >> 8)) & 0xFF);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  livod::io::Ipv4ReassemblyLimits limits;
  limits.max_pending_sets = 3;
  limits.timeout_ns = 1000;
  livod::io::Ipv4Reassembler reassembler(limits);
  std::array<bool, 4> tainted{};
  std::vector<std::byte> payload;
  std::int64_t now = 0;

  for (std::size_t at = 0; at + 5 <= size; at += 5) {
    const std::uint8_t control = data[at];
    if (control == 0xFF) {
      reassembler.flush();
      continue;
    }
    const unsigned datagram = control & 0x3;
    const bool more = (control & 0x4) != 0;
    const bool corrupt = (control & 0x8) != 0;
    const unsigned step = control >> 4;
    now += step == 15 ? -5000 : static_cast<std::int64_t>(step) * 100;
    const std::uint32_t offset = ((std::uint32_t{data[at + 1]} << 8 | data[at + 2]) & 0x1FFF) * 8;
    const std::size_t length = (std::size_t{data[at + 3]} << 8 | data[at + 4]) & 0x7FF;

    payload.resize(length);
    for (std::size_t i = 0; i < length; ++i) {
      payload[i] = pattern(datagram, offset + i);
      if (corrupt) payload[i] ^= static_cast<std::byte>(data[(at + i) % size] | 1);
    }
    if (corrupt) tainted[datagram] = true;

    const livod::io::Ipv4Fragment fragment{
        {0x0A000001, 0x0A000002, static_cast<std::uint16_t>(datagram), 17}, offset, more, payload};
    const auto result = reassembler.add(fragment, now);
    if (reassembler.pending_sets() > limits.max_pending_sets) std::abort();
    if (result.status != livod::io::Ipv4Reassembler::Status::complete) continue;
    if (result.datagram.size() > limits.max_datagram_bytes) std::abort();
    if (!tainted[datagram]) {
      for (std::size_t i = 0; i < result.datagram.size(); ++i) {
        if (result.datagram[i] != pattern(datagram, i)) std::abort();
      }
    }
    tainted[datagram] = false;
  }
  const auto& stats = reassembler.stats();
  if (stats.reassembled + stats.incomplete() + stats.conflicts > stats.fragments) std::abort();
  return 0;
}
