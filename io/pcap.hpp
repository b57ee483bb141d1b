#pragma once
// pcap / pcapng reading and pcap writing (libpcap), with IPv4 fragment reassembly and UDP port
// demultiplexing. No sensor knowledge: a datagram is bytes plus addressing and the record time.
//
// INTERFACE CONTRACT (implemented in io/pcap.cpp): drivers and tools code against this header.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace livod::io {

// One complete UDP datagram from a capture (after IPv4 reassembly when it was fragmented).
struct UdpDatagram {
  std::int64_t capture_time_ns = 0;  // pcap record time of the last fragment (UTC epoch ns)
  std::uint32_t src_ip = 0;          // host byte order
  std::uint32_t dst_ip = 0;          // host byte order
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::uint64_t record_index = 0;    // 0-based index of the pcap record that completed it
  std::span<const std::byte> payload;  // valid until the next call to next()
};

struct PcapStats {
  std::uint64_t records = 0;               // pcap records read
  std::uint64_t udp_datagrams = 0;         // complete datagrams returned
  std::uint64_t non_udp = 0;               // records that are not IPv4/UDP (skipped)
  std::uint64_t fragments = 0;             // IPv4 fragments seen
  std::uint64_t reassembled = 0;           // datagrams rebuilt from fragments
  std::uint64_t incomplete_fragments = 0;  // fragment sets never completed (dropped)
  std::uint64_t malformed = 0;             // truncated/inconsistent headers (counted and skipped)
  std::uint64_t filtered = 0;              // datagrams dropped by the port filter
};

class PcapReader {
 public:
  // Opens a pcap or pcapng file (libpcap detects which). Throws livod::Error with the path and the
  // libpcap message if it cannot be opened or is not a capture file.
  explicit PcapReader(const std::filesystem::path& path);
  ~PcapReader();
  PcapReader(PcapReader&&) noexcept;
  PcapReader& operator=(PcapReader&&) noexcept;
  PcapReader(const PcapReader&) = delete;
  PcapReader& operator=(const PcapReader&) = delete;

  // Only datagrams whose destination port is in `ports` are returned (empty = all).
  void set_port_filter(std::vector<std::uint16_t> ports);

  // The next complete UDP datagram, or nullopt at the end of the file. A truncated final record
  // ends the file and is counted as malformed (it does not throw); a corrupt file header throws
  // livod::FormatError with the byte offset.
  std::optional<UdpDatagram> next();

  // Back to the first record (stats are kept).
  void rewind();

  [[nodiscard]] const PcapStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Writes Ethernet/IPv4/UDP records to a classic pcap file (microsecond or nanosecond resolution).
// Datagrams larger than `mtu` are split into IPv4 fragments, as a real network would.
class PcapWriter {
 public:
  struct Options {
    bool nanosecond_resolution = true;
    std::size_t mtu = 1500;  // IPv4 packet size limit; larger datagrams are fragmented
  };
  PcapWriter(const std::filesystem::path& path, Options options);
  explicit PcapWriter(const std::filesystem::path& path) : PcapWriter(path, Options{}) {}
  ~PcapWriter();
  PcapWriter(PcapWriter&&) noexcept;
  PcapWriter& operator=(PcapWriter&&) noexcept;
  PcapWriter(const PcapWriter&) = delete;
  PcapWriter& operator=(const PcapWriter&) = delete;

  void write_udp(std::int64_t capture_time_ns, std::uint32_t src_ip, std::uint16_t src_port,
                 std::uint32_t dst_ip, std::uint16_t dst_port, std::span<const std::byte> payload);
  void flush();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace livod::io
