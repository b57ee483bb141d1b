#pragma once
// Sizes and fields of the Ethernet, IPv4 and UDP headers that both the pcap reader (io/pcap.cpp)
// and the pcap record writer (io/pcap_records.cpp) parse or build.

#include <cstddef>
#include <cstdint>

namespace livod::io {

inline constexpr std::uint16_t kEthertypeIpv4 = 0x0800;
inline constexpr std::size_t kEthernetHeader = 14;  // destination, source, EtherType
inline constexpr std::uint8_t kIpProtoUdp = 17;
inline constexpr std::uint16_t kIpMoreFragments = 0x2000;  // IPv4 flags: more fragments follow
inline constexpr std::size_t kUdpHeader = 8;

}  // namespace livod::io
