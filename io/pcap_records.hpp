#pragma once
// Classic pcap bytes for UDP datagrams: the file header and one record per Ethernet/IPv4/UDP
// frame, built in memory. PcapWriter (io/pcap.hpp) writes them through stdio; `livod record`
// (daemon/record/) collects them into blocks that it writes whole, so that a file on a full disk
// or of a killed process always ends at a record boundary or inside its last record.
//
// The bytes are those libpcap writes: the 24-byte header and the 16-byte record headers in the
// host's byte order (readers detect it from the magic number), link type Ethernet.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace livod::io {

struct PcapRecordFormat {
  bool nanosecond_resolution = true;
  std::size_t mtu = 1500;  // IPv4 packet size limit; larger datagrams are fragmented
};

inline constexpr std::size_t kPcapFileHeaderBytes = 24;
inline constexpr std::size_t kPcapRecordHeaderBytes = 16;

// The file header: magic (nanosecond or microsecond), version 2.4, snaplen 262144, Ethernet.
std::array<std::byte, kPcapFileHeaderBytes> pcap_file_header(bool nanosecond_resolution);

// Builds the records of UDP datagrams. IPv4 header and UDP checksums are correct; each datagram
// gets the next IPv4 identification; MAC addresses are synthesised from the IP addresses
// (02:00:a.b.c.d, or the IPv4 multicast/broadcast MAC); frames shorter than 60 bytes are
// zero-padded like on the wire; datagrams larger than the MTU are split into IPv4 fragments, one
// record each. With microsecond resolution record times are truncated to whole microseconds.
class UdpPcapEncoder {
 public:
  // Throws std::invalid_argument unless 68 <= mtu <= 65535.
  explicit UdpPcapEncoder(PcapRecordFormat format = {});

  // Appends the datagram's record(s) to `out` (which keeps its capacity: no allocation once it is
  // large enough). Throws std::invalid_argument if the payload exceeds 65507 bytes (the UDP/IPv4
  // maximum) or the time does not fit a pcap record (before 1970 or after 2106); `out` is then
  // unchanged.
  void append(std::vector<std::byte>& out, std::int64_t capture_time_ns, std::uint32_t src_ip,
              std::uint16_t src_port, std::uint32_t dst_ip, std::uint16_t dst_port,
              std::span<const std::byte> payload);

  // Bytes append() adds for a payload of `payload_bytes` (records included).
  [[nodiscard]] std::size_t record_bytes(std::size_t payload_bytes) const;

  [[nodiscard]] const PcapRecordFormat& format() const { return format_; }

 private:
  PcapRecordFormat format_;
  std::uint16_t next_ip_id_ = 1;
  std::vector<std::byte> udp_;  // UDP header + payload, reused
};

}  // namespace livod::io
