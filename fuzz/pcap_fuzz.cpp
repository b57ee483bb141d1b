// libFuzzer target: the pcap/pcapng reader (libpcap parsing, link layers, IPv4/UDP checks and
// fragment reassembly) on arbitrary bytes, read from memory through fmemopen.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "core/error.hpp"
#include "io/pcap.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  try {
    auto reader = livod::io::PcapReader::from_memory(bytes, "fuzz");
    // Alternate the port filter on the input size so both paths are exercised.
    if (size % 2 == 1) reader.set_port_filter({7502, 2368});
    std::uint64_t returned = 0;
    unsigned checksum = 0;
    while (auto datagram = reader.next()) {
      // No UDP payload can exceed 65535 - 20 - 8 bytes; touching every byte lets ASan check that
      // the span really points into live memory.
      if (datagram->payload.size() > 65507) std::abort();
      for (const auto b : datagram->payload) checksum += std::to_integer<unsigned>(b);
      ++returned;
    }
    const auto& stats = reader.stats();
    // Skipped stretches lie inside the input.
    if (stats.udp_datagrams != returned || stats.reassembled > stats.fragments ||
        reader.next().has_value() || reader.losses().bytes() > size) {
      std::abort();
    }
    static_cast<void>(checksum);
  } catch (const livod::FormatError&) {
    // Not a capture: the expected outcome for most inputs.
  }
  return 0;
}
