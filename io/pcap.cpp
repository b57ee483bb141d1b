#include "io/pcap.hpp"

#include <fcntl.h>
#include <pcap/pcap.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/error.hpp"
#include "core/time.hpp"
#include "io/packet_headers.hpp"
#include "io/pcap_records.hpp"

namespace livod::io {

namespace {

constexpr std::uint16_t kEthertypeVlan = 0x8100;     // 802.1Q
constexpr std::uint16_t kEthertypeQinQ = 0x88A8;     // 802.1ad service tag
constexpr std::uint16_t kEthertypeQinQOld = 0x9100;  // pre-standard double tagging
constexpr std::size_t kMaxVlanTags = 8;              // bound on the tag loop; real stacks use 2
constexpr std::size_t kVlanTag = 4;
constexpr std::size_t kSllHeader = 16;
constexpr std::size_t kSll2Header = 20;
constexpr std::size_t kNullHeader = 4;
constexpr std::uint32_t kAfInet = 2;  // AF_INET in every BSD loopback header
constexpr std::size_t kIpv4MinHeader = 20;
constexpr std::uint16_t kIpOffsetMask = 0x1FFF;
constexpr int kWriterSnaplen = 262144;  // libpcap's MAXIMUM_SNAPLEN
// Resynchronisation after a damaged record (see RecordScanner).
constexpr std::uint32_t kMaxRecordBytes = 262144;        // libpcap's largest snapshot length
constexpr std::int64_t kMaxResyncTimeJumpS = 24 * 3600;  // a candidate record's time vs the last
constexpr int kResyncChain = 3;  // records that must follow a candidate (or the end of the file)
constexpr std::uint32_t kPcapngShb = 0x0A0D0D0A;
constexpr std::uint32_t kPcapngByteOrder = 0x1A2B3C4D;
constexpr std::uint32_t kPcapngEpb = 6;

std::uint16_t be16(std::span<const std::byte> b, std::size_t at) {
  return static_cast<std::uint16_t>((std::to_integer<unsigned>(b[at]) << 8) |
                                    std::to_integer<unsigned>(b[at + 1]));
}

std::uint32_t be32(std::span<const std::byte> b, std::size_t at) {
  return (std::uint32_t{be16(b, at)} << 16) | be16(b, at + 2);
}

std::uint32_t le32(std::span<const std::byte> b, std::size_t at) {
  return std::to_integer<std::uint32_t>(b[at]) | (std::to_integer<std::uint32_t>(b[at + 1]) << 8) |
         (std::to_integer<std::uint32_t>(b[at + 2]) << 16) |
         (std::to_integer<std::uint32_t>(b[at + 3]) << 24);
}

// What the link layer carried: an IPv4 packet, something else, or a header that does not fit.
enum class LinkResult { ipv4, other, malformed };

// Skips 802.1Q / 802.1ad tags starting at `pos` (which points after an ethertype that was a tag
// type); returns the inner ethertype and moves `pos` past the tags.
LinkResult skip_vlan_tags(std::span<const std::byte> frame, std::uint16_t& ethertype,
                          std::size_t& pos) {
  std::size_t tags = 0;
  while (ethertype == kEthertypeVlan || ethertype == kEthertypeQinQ ||
         ethertype == kEthertypeQinQOld) {
    if (++tags > kMaxVlanTags || pos + kVlanTag > frame.size()) return LinkResult::malformed;
    ethertype = be16(frame, pos + 2);
    pos += kVlanTag;
  }
  return ethertype == kEthertypeIpv4 ? LinkResult::ipv4 : LinkResult::other;
}

// Finds the IPv4 packet inside one record of link type `dlt`.
LinkResult locate_ipv4(int dlt, std::span<const std::byte> frame,
                       std::span<const std::byte>& ipv4) {
  std::size_t pos = 0;
  LinkResult result = LinkResult::other;
  switch (dlt) {
    case DLT_EN10MB: {
      if (frame.size() < kEthernetHeader) return LinkResult::malformed;
      std::uint16_t ethertype = be16(frame, 12);
      pos = kEthernetHeader;
      result = skip_vlan_tags(frame, ethertype, pos);
      break;
    }
    case DLT_LINUX_SLL: {
      if (frame.size() < kSllHeader) return LinkResult::malformed;
      std::uint16_t protocol = be16(frame, 14);
      pos = kSllHeader;
      result = skip_vlan_tags(frame, protocol, pos);
      break;
    }
    case DLT_LINUX_SLL2: {
      if (frame.size() < kSll2Header) return LinkResult::malformed;
      std::uint16_t protocol = be16(frame, 0);
      pos = kSll2Header;
      result = skip_vlan_tags(frame, protocol, pos);
      break;
    }
    case DLT_NULL:
    case DLT_LOOP: {
      // DLT_NULL stores the address family in the capturing host's byte order, DLT_LOOP in
      // network order; AF_INET is 2 everywhere, so accept either order.
      if (frame.size() < kNullHeader) return LinkResult::malformed;
      const bool inet = le32(frame, 0) == kAfInet || be32(frame, 0) == kAfInet;
      pos = kNullHeader;
      result = inet ? LinkResult::ipv4 : LinkResult::other;
      break;
    }
    case DLT_RAW:
    case DLT_IPV4: {
      if (frame.empty()) return LinkResult::malformed;
      // DLT_RAW may also carry IPv6: the version nibble tells.
      result =
          (std::to_integer<unsigned>(frame[0]) >> 4) == 4 ? LinkResult::ipv4 : LinkResult::other;
      break;
    }
    default:
      return LinkResult::other;
  }
  if (result == LinkResult::ipv4) ipv4 = frame.subspan(pos);
  return result;
}

// Record time in ns; false if it does not fit an int64 (possible in a corrupt pcapng).
bool record_time_ns(const pcap_pkthdr& header, std::int64_t& out) {
  std::int64_t seconds_ns = 0;
  if (__builtin_mul_overflow(static_cast<std::int64_t>(header.ts.tv_sec), kNsPerSecond,
                             &seconds_ns)) {
    return false;
  }
  // The reader is opened with nanosecond precision, so tv_usec holds nanoseconds.
  return !__builtin_add_overflow(seconds_ns, static_cast<std::int64_t>(header.ts.tv_usec), &out);
}

// Random access to the raw bytes of the capture, beside libpcap's own stream.
class RawBytes {
 public:
  RawBytes() = default;
  RawBytes(const RawBytes&) = delete;
  RawBytes& operator=(const RawBytes&) = delete;
  ~RawBytes() { close_fd(); }

  void open_file(const std::filesystem::path& path) {
    close_fd();
    memory_ = {};
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    size_ = 0;
    if (fd_ >= 0) {
      const off_t end = ::lseek(fd_, 0, SEEK_END);
      size_ = end > 0 ? static_cast<std::uint64_t>(end) : 0;
    }
  }
  void use_memory(std::span<const std::byte> bytes) {
    close_fd();
    memory_ = bytes;
    size_ = bytes.size();
  }
  [[nodiscard]] std::uint64_t size() const { return size_; }
  // Reads n bytes at `offset`; false when they are not all there.
  bool read(std::uint64_t offset, std::byte* out, std::size_t n) const {
    if (offset > size_ || n > size_ - offset) return false;
    if (fd_ < 0) {
      if (n > 0) std::memcpy(out, memory_.data() + offset, n);
      return true;
    }
    std::size_t done = 0;
    while (done < n) {
      const ssize_t got = ::pread(fd_, out + done, n - done, static_cast<off_t>(offset + done));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      done += static_cast<std::size_t>(got);
    }
    return true;
  }

 private:
  void close_fd() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  int fd_ = -1;
  std::span<const std::byte> memory_;
  std::uint64_t size_ = 0;
};

// Finds where the records of a damaged capture resume. libpcap cannot resynchronise after a
// corrupt record header, so on an error the reader asks the scanner for the next offset at which
// a plausible record starts that is followed by kResyncChain more plausible records (or the end
// of the file), and continues there. Classic pcap: a record header whose capture length fits the
// file and libpcap's limit, is at most the original length, has a sub-second part below one
// second and a time within a day of the last good record. pcapng: a block of a known type whose
// total length is a multiple of 4 and repeated at its end (blocks are 4-byte aligned).
class RecordScanner {
 public:
  // Learns the format from the file header; false if it is neither pcap nor pcapng.
  bool init(const RawBytes& raw) {
    std::array<std::byte, 24> h{};
    if (!raw.read(0, h.data(), h.size())) return false;
    const std::uint32_t magic_le = le32(h, 0);
    const std::uint32_t magic_be = be32(h, 0);
    ng_ = magic_le == kPcapngShb;
    if (ng_) {
      big_endian_ = be32(h, 8) == kPcapngByteOrder;
      return big_endian_ || le32(h, 8) == kPcapngByteOrder;
    }
    for (const bool big : {false, true}) {
      const std::uint32_t m = big ? magic_be : magic_le;
      if (m == 0xA1B2C3D4 || m == 0xA1B23C4D || m == 0xA1B2CD34) {
        big_endian_ = big;
        fraction_limit_ = m == 0xA1B23C4D ? 1'000'000'000U : 1'000'000U;
        header_bytes_ = m == 0xA1B2CD34 ? 24 : 16;  // Kuznetzov's modified format adds 8 bytes
        return true;
      }
    }
    return false;
  }

  [[nodiscard]] bool pcapng() const { return ng_; }

  // The first offset >= `from` where records resume, or nullopt when none does before the end.
  std::optional<std::uint64_t> resume_after(const RawBytes& raw, std::uint64_t from,
                                            std::optional<std::int64_t> last_seconds) const {
    std::uint64_t pos = from;
    if (ng_ && pos % 4 != 0) pos += 4 - pos % 4;
    const std::uint64_t step = ng_ ? 4 : 1;
    // Scan a window at a time rather than byte by byte through pread.
    constexpr std::size_t kWindow = 1 << 16;
    std::vector<std::byte> window;
    while (pos + minimum_record() <= raw.size()) {
      const std::size_t n =
          static_cast<std::size_t>(std::min<std::uint64_t>(kWindow, raw.size() - pos));
      window.resize(n);
      if (!raw.read(pos, window.data(), n)) return std::nullopt;
      for (std::size_t i = 0; i + minimum_record() <= n; i += step) {
        if (!quick_check(std::span<const std::byte>(window).subspan(i), pos + i, raw.size(),
                         last_seconds)) {
          continue;
        }
        if (chain_ok(raw, pos + i, last_seconds)) return pos + i;
      }
      if (n <= minimum_record()) break;
      pos += n - minimum_record() + step;
      if (ng_ && pos % 4 != 0) pos += 4 - pos % 4;
    }
    return std::nullopt;
  }

 private:
  [[nodiscard]] std::size_t minimum_record() const { return ng_ ? 12 : header_bytes_; }

  [[nodiscard]] std::uint32_t u32(std::span<const std::byte> b, std::size_t at) const {
    return big_endian_ ? be32(b, at) : le32(b, at);
  }

  // Checks what the record header alone can tell; on success `next` is the following record.
  bool record_ok(std::span<const std::byte> b, std::uint64_t at, std::uint64_t file_size,
                 std::optional<std::int64_t> last_seconds, std::uint64_t& next) const {
    if (ng_) {
      const std::uint32_t type = u32(b, 0);
      const std::uint32_t length = u32(b, 4);
      const bool known =
          type == kPcapngShb || (type >= 1 && type <= 10) || type == 0xBAD || type == 0x40000BAD;
      if (!known || length < 12 || length % 4 != 0 || length > file_size - at) return false;
      if (type == kPcapngEpb && length < 32) return false;
      next = at + length;
      return true;
    }
    const std::uint32_t seconds = u32(b, 0);
    const std::uint32_t fraction = u32(b, 4);
    const std::uint32_t caplen = u32(b, 8);
    const std::uint32_t len = u32(b, 12);
    if (caplen > kMaxRecordBytes || len > kMaxRecordBytes || caplen > len || caplen == 0 ||
        fraction >= fraction_limit_) {
      return false;
    }
    if (last_seconds &&
        std::llabs(static_cast<std::int64_t>(seconds) - *last_seconds) > kMaxResyncTimeJumpS) {
      return false;
    }
    if (header_bytes_ + std::uint64_t{caplen} > file_size - at) return false;
    next = at + header_bytes_ + caplen;
    return true;
  }

  bool quick_check(std::span<const std::byte> b, std::uint64_t at, std::uint64_t file_size,
                   std::optional<std::int64_t> last_seconds) const {
    std::uint64_t next = 0;
    return record_ok(b, at, file_size, last_seconds, next);
  }

  // The record at `at` and the kResyncChain records after it are plausible (pcapng: their
  // trailing lengths match), or the file ends cleanly after one of them.
  bool chain_ok(const RawBytes& raw, std::uint64_t at,
                std::optional<std::int64_t> last_seconds) const {
    std::array<std::byte, 24> h{};
    std::uint64_t pos = at;
    for (int k = 0; k <= kResyncChain; ++k) {
      if (pos == raw.size()) return k > 0;
      const std::size_t n = minimum_record();
      if (!raw.read(pos, h.data(), n)) return false;
      std::uint64_t next = 0;
      if (!record_ok(std::span<const std::byte>(h).first(n), pos, raw.size(), last_seconds, next)) {
        return false;
      }
      if (ng_) {
        std::array<std::byte, 4> trailer{};
        if (!raw.read(next - 4, trailer.data(), 4) || u32(trailer, 0) != u32(h, 4)) return false;
      }
      pos = next;
    }
    return true;
  }

  bool ng_ = false;
  bool big_endian_ = false;
  std::uint32_t fraction_limit_ = 1'000'000U;
  std::size_t header_bytes_ = 16;
};

struct PcapCloser {
  void operator()(pcap_t* p) const { pcap_close(p); }
};
using PcapHandle = std::unique_ptr<pcap_t, PcapCloser>;

struct DumperCloser {
  void operator()(pcap_dumper_t* d) const { pcap_dump_close(d); }
};
using DumperHandle = std::unique_ptr<pcap_dumper_t, DumperCloser>;

}  // namespace

// ------------------------------------------------------------------------------------------------
// Reader

struct PcapReader::Impl {
  std::string source;          // path or memory name, for messages
  std::filesystem::path path;  // empty when reading from memory
  std::vector<std::byte> memory;
  bool in_memory = false;

  PcapHandle pcap;
  int dlt = DLT_EN10MB;
  bool pcapng = false;
  std::vector<std::uint16_t> ports;  // sorted; empty = all
  Ipv4Reassembler reassembler;
  std::uint64_t incomplete_seen = 0;  // reassembler.stats().incomplete() already in `stats`
  PcapStats stats;
  std::string end_error;
  bool finished = false;
  std::uint64_t next_record_index = 0;
  bool have_record_time = false;  // min/max_record_time_ns are set
  // Reading past damage.
  RawBytes raw;
  RecordScanner scanner;
  bool scanner_ok = false;
  std::uint64_t first_record_pos = 0;  // after the file header (pcapng: after the first blocks)
  std::optional<std::int64_t> last_good_ns;  // time of the last record read
  bool loss_open = false;  // the last loss waits for the time of the next good record
  InputLossLog losses;

  // Handles a record libpcap could not read at `record_start`; false when the file ends there.
  bool skip_damage(std::uint64_t record_start, const std::string& message);

  void open();
  void sync_incomplete();
  void finish();
  std::optional<UdpDatagram> decode(std::span<const std::byte> frame, bool frame_complete,
                                    std::int64_t time_ns, std::uint64_t record_index);
};

void PcapReader::Impl::open() {
  FILE* file = nullptr;
  if (in_memory) {
    if (memory.empty()) throw FormatError(source, 0, "empty input, not a pcap/pcapng capture");
    // fmemopen never writes through a read-only stream; the buffer is owned by this Impl.
    file = fmemopen(memory.data(), memory.size(), "rb");
  } else {
    file = std::fopen(path.c_str(), "rb");
  }
  if (file == nullptr) {
    throw Error(source + ": cannot open: " + std::strerror(errno));
  }
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  pcap_t* p = pcap_fopen_offline_with_tstamp_precision(file, PCAP_TSTAMP_PRECISION_NANO, errbuf);
  if (p == nullptr) {
    // On failure libpcap leaves the FILE to us; its position is where header parsing stopped.
    const long position = std::ftell(file);
    std::fclose(file);
    const std::string message = errbuf;
    const bool bad_magic = message.find("unknown file format") != std::string::npos;
    throw FormatError(source, bad_magic || position < 0 ? 0 : static_cast<std::uint64_t>(position),
                      "not a readable pcap/pcapng capture: " + message);
  }
  pcap.reset(p);
  if (in_memory) {
    raw.use_memory(memory);
  } else {
    raw.open_file(path);
  }
  scanner_ok = scanner.init(raw);
  {
    const long position = std::ftell(pcap_file(p));
    first_record_pos = position < 0 ? 0 : static_cast<std::uint64_t>(position);
  }
  dlt = pcap_datalink(p);
  // libpcap reports the pcapng section header version (1.0) as the file version; classic pcap is
  // 2.4.
  pcapng = pcap_major_version(p) == 1;
  finished = false;
  next_record_index = 0;
}

void PcapReader::Impl::sync_incomplete() {
  const std::uint64_t now = reassembler.stats().incomplete();
  stats.incomplete_fragments += now - incomplete_seen;
  incomplete_seen = now;
}

void PcapReader::Impl::finish() {
  reassembler.flush();
  sync_incomplete();
  finished = true;
}

bool PcapReader::Impl::skip_damage(std::uint64_t record_start, const std::string& message) {
  InputLoss loss;
  loss.file = source;
  loss.byte_offset = record_start;
  loss.reason = message;
  std::optional<std::uint64_t> resume;
  if (scanner_ok) {
    std::optional<std::int64_t> last_seconds;
    if (last_good_ns) last_seconds = *last_good_ns / kNsPerSecond;
    resume = scanner.resume_after(raw, record_start + 1, last_seconds);
  }
  const std::uint64_t end = resume ? *resume : std::max(raw.size(), record_start);
  loss.bytes = end - record_start;
  // The records in the stretch are not known; estimate them from the average record size.
  if (stats.records > 0 && record_start > first_record_pos && loss.bytes > 0) {
    const double average =
        static_cast<double>(record_start - first_record_pos) / static_cast<double>(stats.records);
    loss.records = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(static_cast<double>(loss.bytes) / average + 0.5));
    loss.records_estimated = true;
  } else {
    loss.records = 1;
    loss.records_estimated = true;
  }
  if (!resume) loss.reason += " (the file ends in the damage)";
  losses.add(std::move(loss));
  loss_open = resume.has_value();
  if (!resume) return false;
  return std::fseek(pcap_file(pcap.get()), static_cast<long>(*resume), SEEK_SET) == 0;
}

std::optional<UdpDatagram> PcapReader::Impl::decode(std::span<const std::byte> frame,
                                                    bool frame_complete, std::int64_t time_ns,
                                                    std::uint64_t record_index) {
  std::span<const std::byte> ip;
  switch (locate_ipv4(dlt, frame, ip)) {
    case LinkResult::other:
      ++stats.non_udp;
      return std::nullopt;
    case LinkResult::malformed:
      ++stats.malformed;
      return std::nullopt;
    case LinkResult::ipv4:
      break;
  }

  if (ip.size() < kIpv4MinHeader || (std::to_integer<unsigned>(ip[0]) >> 4) != 4) {
    ++stats.malformed;
    return std::nullopt;
  }
  const std::size_t header_bytes = (std::to_integer<std::size_t>(ip[0]) & 0x0F) * 4;
  std::size_t total_length = be16(ip, 2);
  const std::uint16_t flags_offset = be16(ip, 6);
  const bool is_fragment = (flags_offset & (kIpMoreFragments | kIpOffsetMask)) != 0;
  // total_length < ip.size() is normal: Ethernet pads short frames.
  if (header_bytes < kIpv4MinHeader || total_length < header_bytes || header_bytes > ip.size()) {
    ++stats.malformed;
    return std::nullopt;
  }
  if (total_length > ip.size()) {
    // Some sensors send a wrong total length (VLP-16 position packets say 1234 for a 540-byte
    // packet). When the record holds the whole frame and this is not a fragment, the frame end
    // bounds the packet and the UDP length still has to fit; otherwise the data is missing.
    if (!frame_complete || is_fragment) {
      ++stats.malformed;
      return std::nullopt;
    }
    ++stats.ip_length_clamped;
    total_length = ip.size();
  }
  const std::uint8_t protocol = std::to_integer<std::uint8_t>(ip[9]);
  const std::uint32_t src_ip = be32(ip, 12);
  const std::uint32_t dst_ip = be32(ip, 16);
  const auto ip_payload = ip.subspan(header_bytes, total_length - header_bytes);
  const bool more_fragments = (flags_offset & kIpMoreFragments) != 0;
  const std::uint32_t fragment_offset =
      static_cast<std::uint32_t>(flags_offset & kIpOffsetMask) * 8U;

  std::span<const std::byte> udp;
  if (is_fragment) {
    ++stats.fragments;
    if (protocol != kIpProtoUdp) {
      ++stats.non_udp;
      return std::nullopt;
    }
    const Ipv4Fragment fragment{
        {src_ip, dst_ip, be16(ip, 4), protocol}, fragment_offset, more_fragments, ip_payload};
    const auto result = reassembler.add(fragment, time_ns);
    sync_incomplete();
    switch (result.status) {
      case Ipv4Reassembler::Status::pending:
      case Ipv4Reassembler::Status::duplicate:
        return std::nullopt;
      case Ipv4Reassembler::Status::invalid:
      case Ipv4Reassembler::Status::conflict:
        ++stats.malformed;
        return std::nullopt;
      case Ipv4Reassembler::Status::complete:
        ++stats.reassembled;
        udp = result.datagram;
        break;
    }
  } else if (protocol != kIpProtoUdp) {
    ++stats.non_udp;
    return std::nullopt;
  } else {
    udp = ip_payload;
  }

  if (udp.size() < kUdpHeader) {
    ++stats.malformed;
    return std::nullopt;
  }
  const std::size_t udp_length = be16(udp, 4);
  if (udp_length < kUdpHeader || udp_length > udp.size()) {
    ++stats.malformed;
    return std::nullopt;
  }
  UdpDatagram datagram;
  datagram.capture_time_ns = time_ns;
  datagram.src_ip = src_ip;
  datagram.dst_ip = dst_ip;
  datagram.src_port = be16(udp, 0);
  datagram.dst_port = be16(udp, 2);
  datagram.record_index = record_index;
  datagram.payload = udp.subspan(kUdpHeader, udp_length - kUdpHeader);
  if (!ports.empty() && !std::binary_search(ports.begin(), ports.end(), datagram.dst_port)) {
    ++stats.filtered;
    return std::nullopt;
  }
  ++stats.udp_datagrams;
  return datagram;
}

PcapReader::PcapReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {
  impl_->open();
}

PcapReader::PcapReader(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  impl_->source = path.string();
  impl_->path = path;
  impl_->open();
}

PcapReader PcapReader::from_memory(std::span<const std::byte> bytes, std::string name) {
  auto impl = std::make_unique<Impl>();
  impl->source = std::move(name);
  impl->memory.assign(bytes.begin(), bytes.end());
  impl->in_memory = true;
  return PcapReader(std::move(impl));
}

PcapReader::~PcapReader() = default;
PcapReader::PcapReader(PcapReader&&) noexcept = default;
PcapReader& PcapReader::operator=(PcapReader&&) noexcept = default;

void PcapReader::set_port_filter(std::vector<std::uint16_t> ports) {
  std::sort(ports.begin(), ports.end());
  ports.erase(std::unique(ports.begin(), ports.end()), ports.end());
  impl_->ports = std::move(ports);
}

std::optional<UdpDatagram> PcapReader::next() {
  Impl& s = *impl_;
  while (!s.finished) {
    pcap_pkthdr* header = nullptr;
    const u_char* data = nullptr;
    const long start = std::ftell(pcap_file(s.pcap.get()));
    const std::uint64_t record_start = start < 0 ? 0 : static_cast<std::uint64_t>(start);
    const int rc = pcap_next_ex(s.pcap.get(), &header, &data);
    if (rc == PCAP_ERROR_BREAK) {  // clean end of file
      s.finish();
      break;
    }
    if (rc != 1) {
      // A truncated or corrupt record: libpcap cannot resynchronise, so the scanner finds where
      // the records resume and the reader continues there; the stretch is an InputLoss.
      ++s.stats.malformed;
      const std::string message = pcap_geterr(s.pcap.get());
      if (!s.skip_damage(record_start, message)) {
        s.end_error = "at byte offset " + std::to_string(record_start) + ": " + message;
        s.finish();
        break;
      }
      continue;
    }
    const std::uint64_t index = s.next_record_index++;
    std::int64_t time_ns = 0;
    if (!record_time_ns(*header, time_ns)) {
      ++s.stats.records;
      ++s.stats.malformed;
      continue;
    }
    if (s.loss_open) {
      s.loss_open = false;
      if (s.last_good_ns && time_ns >= *s.last_good_ns) {
        s.losses.set_last_seconds(static_cast<double>(time_ns - *s.last_good_ns) / 1e9);
      }
    }
    s.last_good_ns = time_ns;
    if (!s.have_record_time) {
      s.have_record_time = true;
      s.stats.min_record_time_ns = time_ns;
      s.stats.max_record_time_ns = time_ns;
    } else {
      s.stats.min_record_time_ns = std::min(s.stats.min_record_time_ns, time_ns);
      s.stats.max_record_time_ns = std::max(s.stats.max_record_time_ns, time_ns);
    }
    ++s.stats.records;
    const std::span<const std::byte> frame(reinterpret_cast<const std::byte*>(data),
                                           header->caplen);
    const bool frame_complete = header->caplen >= header->len;
    if (auto datagram = s.decode(frame, frame_complete, time_ns, index)) return datagram;
  }
  return std::nullopt;
}

void PcapReader::rewind() {
  impl_->reassembler.flush();
  impl_->sync_incomplete();
  impl_->end_error.clear();
  impl_->losses = InputLossLog{};
  impl_->loss_open = false;
  impl_->last_good_ns.reset();
  impl_->pcap.reset();
  impl_->open();
}

const PcapStats& PcapReader::stats() const {
  return impl_->stats;
}

void PcapReader::set_reassembly_limits(const Ipv4ReassemblyLimits& limits) {
  impl_->reassembler.flush();
  impl_->sync_incomplete();
  impl_->reassembler = Ipv4Reassembler(limits);
  impl_->incomplete_seen = 0;
}

const Ipv4ReassemblyStats& PcapReader::reassembly_stats() const {
  return impl_->reassembler.stats();
}

int PcapReader::link_type() const {
  return impl_->dlt;
}

std::string PcapReader::link_type_name() const {
  const char* name = pcap_datalink_val_to_name(impl_->dlt);
  return name != nullptr ? name : "DLT " + std::to_string(impl_->dlt);
}

bool PcapReader::is_pcapng() const {
  return impl_->pcapng;
}

const std::string& PcapReader::end_error() const {
  return impl_->end_error;
}

const InputLossLog& PcapReader::losses() const {
  return impl_->losses;
}

// ------------------------------------------------------------------------------------------------
// Writer: the records come from UdpPcapEncoder (io/pcap_records.hpp), libpcap's dumper owns the
// file and its header.

struct PcapWriter::Impl {
  std::string source;
  PcapHandle dead;
  DumperHandle dumper;
  UdpPcapEncoder encoder;
  std::vector<std::byte> records;  // one datagram's records, reused

  explicit Impl(const Options& options)
      : encoder(PcapRecordFormat{options.nanosecond_resolution, options.mtu}) {}
};

PcapWriter::PcapWriter(const std::filesystem::path& path, Options options)
    : impl_(std::make_unique<Impl>(options)) {
  impl_->source = path.string();
  const unsigned precision =
      options.nanosecond_resolution ? PCAP_TSTAMP_PRECISION_NANO : PCAP_TSTAMP_PRECISION_MICRO;
  impl_->dead.reset(pcap_open_dead_with_tstamp_precision(DLT_EN10MB, kWriterSnaplen, precision));
  if (!impl_->dead) throw Error(impl_->source + ": pcap_open_dead failed");
  pcap_dumper_t* dumper = pcap_dump_open(impl_->dead.get(), path.c_str());
  if (dumper == nullptr) {
    throw Error(impl_->source + ": cannot create pcap: " + pcap_geterr(impl_->dead.get()));
  }
  impl_->dumper.reset(dumper);
}

PcapWriter::~PcapWriter() = default;
PcapWriter::PcapWriter(PcapWriter&&) noexcept = default;
PcapWriter& PcapWriter::operator=(PcapWriter&&) noexcept = default;

void PcapWriter::write_udp(std::int64_t capture_time_ns, std::uint32_t src_ip,
                           std::uint16_t src_port, std::uint32_t dst_ip, std::uint16_t dst_port,
                           std::span<const std::byte> payload) {
  Impl& s = *impl_;
  s.records.clear();
  s.encoder.append(s.records, capture_time_ns, src_ip, src_port, dst_ip, dst_port, payload);
  // The same bytes pcap_dump() writes: record headers in host order, then the frame.
  std::fwrite(s.records.data(), 1, s.records.size(), pcap_dump_file(s.dumper.get()));
}

void PcapWriter::flush() {
  FILE* file = pcap_dump_file(impl_->dumper.get());
  if (pcap_dump_flush(impl_->dumper.get()) != 0 || std::ferror(file) != 0) {
    throw Error(impl_->source + ": writing the capture failed");
  }
}

}  // namespace livod::io
