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
#include <string>
#include <vector>

#include "io/input_loss.hpp"
#include "io/ipv4_reassembly.hpp"

namespace livod::io {

// One complete UDP datagram from a capture (after IPv4 reassembly when it was fragmented).
struct UdpDatagram {
  std::int64_t capture_time_ns = 0;  // pcap record time of the last fragment (UTC epoch ns)
  std::uint32_t src_ip = 0;          // host byte order
  std::uint32_t dst_ip = 0;          // host byte order
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::uint64_t record_index = 0;      // 0-based index of the pcap record that completed it
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
  // Unfragmented IPv4 packets whose total-length field exceeded the (complete) frame; they were
  // read up to the frame end, the UDP length still had to fit (VLP-16 position packets say 1234).
  std::uint64_t ip_length_clamped = 0;
  // Earliest and latest valid record time seen (UTC epoch ns); 0 until a record was read.
  std::int64_t min_record_time_ns = 0;
  std::int64_t max_record_time_ns = 0;
};

// Link types handled: Ethernet (with up to 8 stacked 802.1Q/802.1ad VLAN tags), Linux cooked SLL
// and SLL2, raw IP (DLT_RAW, DLT_IPV4) and BSD loopback (DLT_NULL, DLT_LOOP). Records of any other
// link type are counted in non_udp. IPv4 and UDP checksums are not verified: captures taken on the
// sending host carry unfinished checksums when the NIC offloads them. Fragments are reassembled
// with an Ipv4Reassembler (bounded, see io/ipv4_reassembly.hpp); sets still open at the end of
// the file count as incomplete_fragments, fragments that are invalid or contradict their set as
// malformed.
class PcapReader {
 public:
  // Opens a pcap or pcapng file (libpcap detects which). Throws livod::Error with the path and the
  // libpcap message if it cannot be opened or is not a capture file.
  explicit PcapReader(const std::filesystem::path& path);
  // Reads a capture held in memory (the bytes are copied; `name` appears in error messages).
  static PcapReader from_memory(std::span<const std::byte> bytes, std::string name = "<memory>");
  ~PcapReader();
  PcapReader(PcapReader&&) noexcept;
  PcapReader& operator=(PcapReader&&) noexcept;
  PcapReader(const PcapReader&) = delete;
  PcapReader& operator=(const PcapReader&) = delete;

  // Only datagrams whose destination port is in `ports` are returned (empty = all).
  void set_port_filter(std::vector<std::uint16_t> ports);

  // The next complete UDP datagram, or nullopt at the end of the file. A corrupt record (a
  // capture length libpcap refuses, a broken pcapng block) does not end the file: the reader
  // scans for the next offset where valid records resume, continues there and records the
  // skipped stretch in losses(); a truncated final record ends the file. Each damaged stretch
  // counts once as malformed. A corrupt file header throws livod::FormatError with the byte
  // offset.
  std::optional<UdpDatagram> next();

  // Back to the first record (stats are kept).
  void rewind();

  [[nodiscard]] const PcapStats& stats() const;

  // Replaces the fragment table (pending sets are dropped and counted as incomplete).
  void set_reassembly_limits(const Ipv4ReassemblyLimits& limits);
  [[nodiscard]] const Ipv4ReassemblyStats& reassembly_stats() const;

  [[nodiscard]] int link_type() const;               // libpcap DLT_* value
  [[nodiscard]] std::string link_type_name() const;  // e.g. "EN10MB", "LINUX_SLL2"
  [[nodiscard]] bool is_pcapng() const;
  // Why reading stopped before a clean end of file (libpcap's message and the byte offset), or
  // empty: the file ended inside damage (a truncated or corrupt final record).
  [[nodiscard]] const std::string& end_error() const;
  // Every stretch of the file that could not be read (byte offset, bytes, estimated records,
  // the recording time it spans), including the one end_error() describes. Empty for an intact
  // capture.
  [[nodiscard]] const InputLossLog& losses() const;

 private:
  struct Impl;
  explicit PcapReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Writes Ethernet/IPv4/UDP records to a classic pcap file (microsecond or nanosecond resolution).
// Datagrams larger than `mtu` are split into IPv4 fragments, as a real network would. Writing is
// classic pcap only (no pcapng). IPv4 header and UDP checksums are correct; each datagram gets the
// next IPv4 identification; MAC addresses are synthesised from the IP addresses (02:00:a.b.c.d,
// or the IPv4 multicast/broadcast MAC); frames shorter than 60 bytes are zero-padded like on the
// wire. With microsecond resolution record times are truncated to whole microseconds.
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

  // Throws std::invalid_argument if the payload exceeds 65507 bytes (the UDP/IPv4 maximum) or the
  // time does not fit a pcap record (before 1970 or after 2106); Options are checked by the
  // constructor (68 <= mtu <= 65535).
  void write_udp(std::int64_t capture_time_ns, std::uint32_t src_ip, std::uint16_t src_port,
                 std::uint32_t dst_ip, std::uint16_t dst_port, std::span<const std::byte> payload);
  // Throws livod::Error if the data could not be written.
  void flush();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace livod::io
