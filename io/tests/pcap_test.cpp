// Tests of the pcap/pcapng reader, the pcap writer and IPv4 reassembly, on the real captures in
// ../shared/data. Expected counts, sizes and payload hashes were derived independently of this
// code: with tshark 4.0 (`tshark -o ip.defragment:TRUE -T fields -e udp.payload ...`, FNV-1a
// computed over its reassembled bytes), from the Ouster metadata JSON (packet size formulas of
// docs sensor-protocols.md section 3) and from the data README (Velodyne packet counts).
//
// Link types and pcapng are tested by re-encoding the real Ethernet captures byte by byte with the
// small independent encoders below (not with the code under test), then checking that the reader
// returns exactly the datagrams it returns for the original.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/ipv4_reassembly.hpp"
#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::io {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::byte>;

// ---------------------------------------------------------------------------------------------
// Independent helpers: raw file access, classic pcap and pcapng encoders, link-layer rewrites.

Bytes read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Bytes out(chars.size());
  std::memcpy(out.data(), chars.data(), chars.size());
  return out;
}

void write_file(const fs::path& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::uint32_t get_le32(const Bytes& b, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | std::to_integer<std::uint32_t>(b[at + i]);
  return v;
}

std::uint16_t get_be16(const Bytes& b, std::size_t at) {
  return static_cast<std::uint16_t>((std::to_integer<unsigned>(b[at]) << 8) |
                                    std::to_integer<unsigned>(b[at + 1]));
}

void append_le(Bytes& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<std::byte>((v >> (8 * i)) & 0xFF));
}

void append_be(Bytes& out, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<std::byte>((v >> (8 * i)) & 0xFF));
}

struct RawRecord {
  std::uint32_t seconds = 0;
  std::uint32_t fraction = 0;  // us or ns
  std::uint32_t original_length = 0;
  Bytes data;
  std::size_t file_offset = 0;  // offset of the record header in the parsed file
};

struct RawPcap {
  bool nanosecond = false;
  std::uint32_t link_type = 1;
  std::uint32_t snaplen = 65535;
  std::vector<RawRecord> records;
};

// Classic little-endian pcap, as every capture in ../shared/data is.
RawPcap parse_pcap(const Bytes& file) {
  RawPcap pcap;
  const std::uint32_t magic = get_le32(file, 0);
  if (magic != 0xA1B2C3D4 && magic != 0xA1B23C4D) throw std::runtime_error("not LE pcap");
  pcap.nanosecond = magic == 0xA1B23C4D;
  pcap.snaplen = get_le32(file, 16);
  pcap.link_type = get_le32(file, 20);
  std::size_t at = 24;
  while (at + 16 <= file.size()) {
    RawRecord r;
    r.file_offset = at;
    r.seconds = get_le32(file, at);
    r.fraction = get_le32(file, at + 4);
    const std::uint32_t caplen = get_le32(file, at + 8);
    r.original_length = get_le32(file, at + 12);
    if (at + 16 + caplen > file.size()) throw std::runtime_error("truncated test input");
    r.data.assign(file.begin() + static_cast<std::ptrdiff_t>(at + 16),
                  file.begin() + static_cast<std::ptrdiff_t>(at + 16 + caplen));
    pcap.records.push_back(std::move(r));
    at += 16 + caplen;
  }
  return pcap;
}

Bytes serialize_pcap(const RawPcap& pcap) {
  Bytes out;
  append_le(out, pcap.nanosecond ? 0xA1B23C4D : 0xA1B2C3D4, 4);
  append_le(out, 2, 2);
  append_le(out, 4, 2);
  append_le(out, 0, 8);
  append_le(out, pcap.snaplen, 4);
  append_le(out, pcap.link_type, 4);
  for (const auto& r : pcap.records) {
    append_le(out, r.seconds, 4);
    append_le(out, r.fraction, 4);
    append_le(out, r.data.size(), 4);
    append_le(out, r.original_length, 4);
    out.insert(out.end(), r.data.begin(), r.data.end());
  }
  return out;
}

// pcapng: section header, one interface (if_tsresol 6 or 9), enhanced packet blocks.
Bytes serialize_pcapng(const RawPcap& pcap) {
  Bytes out;
  append_le(out, 0x0A0D0D0A, 4);
  append_le(out, 28, 4);
  append_le(out, 0x1A2B3C4D, 4);
  append_le(out, 1, 2);
  append_le(out, 0, 2);
  append_le(out, ~std::uint64_t{0}, 8);  // section length unknown
  append_le(out, 28, 4);

  append_le(out, 1, 4);
  append_le(out, 32, 4);
  append_le(out, pcap.link_type, 2);
  append_le(out, 0, 2);
  append_le(out, pcap.snaplen, 4);
  append_le(out, 9, 2);  // if_tsresol
  append_le(out, 1, 2);
  append_le(out, pcap.nanosecond ? 9 : 6, 1);
  append_le(out, 0, 3);  // option padding
  append_le(out, 0, 4);  // opt_endofopt
  append_le(out, 32, 4);

  for (const auto& r : pcap.records) {
    const std::size_t padded = (r.data.size() + 3) / 4 * 4;
    const std::size_t length = 32 + padded;
    const std::uint64_t units =
        std::uint64_t{r.seconds} * (pcap.nanosecond ? 1'000'000'000 : 1'000'000) + r.fraction;
    append_le(out, 6, 4);
    append_le(out, length, 4);
    append_le(out, 0, 4);  // interface id
    append_le(out, units >> 32, 4);
    append_le(out, units & 0xFFFFFFFF, 4);
    append_le(out, r.data.size(), 4);
    append_le(out, r.original_length, 4);
    out.insert(out.end(), r.data.begin(), r.data.end());
    append_le(out, 0, padded - r.data.size());
    append_le(out, length, 4);
  }
  return out;
}

enum class Link { vlan, qinq, sll, sll2, null_le, loop, raw, ipv4 };

// Re-encodes one Ethernet frame for another link type (libpcap LINKTYPE_* numbers).
std::uint32_t link_type_number(Link link) {
  switch (link) {
    case Link::vlan:
    case Link::qinq:
      return 1;
    case Link::sll:
      return 113;
    case Link::sll2:
      return 276;
    case Link::null_le:
      return 0;
    case Link::loop:
      return 108;
    case Link::raw:
      return 101;
    case Link::ipv4:
      return 228;
  }
  return 0;
}

Bytes relink(const Bytes& ethernet, Link link) {
  const Bytes macs(ethernet.begin(), ethernet.begin() + 12);
  const std::uint16_t ethertype = get_be16(ethernet, 12);
  const Bytes payload(ethernet.begin() + 14, ethernet.end());
  Bytes out;
  switch (link) {
    case Link::vlan:
      out = macs;
      append_be(out, 0x8100, 2);
      append_be(out, 0x2064, 2);  // priority 1, VLAN 100
      append_be(out, ethertype, 2);
      break;
    case Link::qinq:
      out = macs;
      append_be(out, 0x88A8, 2);
      append_be(out, 0x0007, 2);
      append_be(out, 0x8100, 2);
      append_be(out, 0x0064, 2);
      append_be(out, ethertype, 2);
      break;
    case Link::sll:
      append_be(out, 0, 2);  // packet to us
      append_be(out, 1, 2);  // ARPHRD_ETHER
      append_be(out, 6, 2);
      out.insert(out.end(), macs.begin() + 6, macs.end());
      append_be(out, 0, 2);
      append_be(out, ethertype, 2);
      break;
    case Link::sll2:
      append_be(out, ethertype, 2);
      append_be(out, 0, 2);
      append_be(out, 3, 4);  // interface index
      append_be(out, 1, 2);  // ARPHRD_ETHER
      out.push_back(std::byte{0});
      out.push_back(std::byte{6});
      out.insert(out.end(), macs.begin() + 6, macs.end());
      append_be(out, 0, 2);
      break;
    case Link::null_le:
      append_le(out, 2, 4);  // AF_INET, little-endian capturing host
      break;
    case Link::loop:
      append_be(out, 2, 4);
      break;
    case Link::raw:
    case Link::ipv4:
      break;
  }
  out.insert(out.end(), payload.begin(), payload.end());
  return out;
}

RawPcap relink(RawPcap pcap, Link link) {
  pcap.link_type = link_type_number(link);
  for (auto& r : pcap.records) {
    r.data = relink(r.data, link);
    r.original_length = static_cast<std::uint32_t>(r.data.size());
  }
  return pcap;
}

std::uint64_t fnv1a64(std::span<const std::byte> bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (auto b : bytes) {
    h ^= std::to_integer<std::uint64_t>(b);
    h *= 0x100000001b3ULL;
  }
  return h;
}

// Ones-complement sum folded to 16 bits; a correct IPv4 header sums to 0xFFFF.
std::uint16_t ones_complement_sum(std::span<const std::byte> bytes) {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i + 1 < bytes.size(); i += 2) {
    sum += (std::to_integer<std::uint32_t>(bytes[i]) << 8) |
           std::to_integer<std::uint32_t>(bytes[i + 1]);
  }
  if (bytes.size() % 2 != 0) sum += std::to_integer<std::uint32_t>(bytes.back()) << 8;
  while ((sum >> 16) != 0) sum = (sum & 0xFFFF) + (sum >> 16);
  return static_cast<std::uint16_t>(sum);
}

constexpr std::uint32_t ip(int a, int b, int c, int d) {
  return (static_cast<std::uint32_t>(a) << 24) | (static_cast<std::uint32_t>(b) << 16) |
         (static_cast<std::uint32_t>(c) << 8) | static_cast<std::uint32_t>(d);
}

// What the tests compare: everything of a datagram, with its payload as size + hash.
struct Seen {
  std::int64_t time_ns = 0;
  std::uint32_t src_ip = 0;
  std::uint32_t dst_ip = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::uint64_t record_index = 0;
  std::size_t size = 0;
  std::uint64_t hash = 0;
  friend bool operator==(const Seen&, const Seen&) = default;
};

std::vector<Seen> read_all(PcapReader& reader) {
  std::vector<Seen> out;
  while (auto d = reader.next()) {
    out.push_back({d->capture_time_ns, d->src_ip, d->dst_ip, d->src_port, d->dst_port,
                   d->record_index, d->payload.size(), fnv1a64(d->payload)});
  }
  return out;
}

std::vector<Seen> read_all(const fs::path& path) {
  PcapReader reader(path);
  return read_all(reader);
}

std::int64_t ns(std::int64_t seconds, std::int64_t nanoseconds) {
  return seconds * 1'000'000'000 + nanoseconds;
}

// Ouster lidar packet sizes (sensor-protocols.md section 3.2/3.3) for 16 columns per packet.
constexpr std::size_t legacy_lidar_bytes(std::size_t pixels) {
  return 16 * (16 + 12 * pixels + 4);
}
constexpr std::size_t non_legacy_lidar_bytes(std::size_t pixels, std::size_t bytes_per_pixel) {
  return 32 + 16 * (12 + bytes_per_pixel * pixels) + 32;
}
constexpr std::size_t kOusterLegacyImuBytes = 48;

// ---------------------------------------------------------------------------------------------
// Real captures

TEST(PcapReader, OusterSamePortsReassemblesLidarAndImuOnOnePort) {
  // same_ports.1.json: 128 px, FUSA_RNG15_RFL8_NIR8_DUAL (8 B/px); same_ports.2.json: 64 px,
  // LEGACY; both sensors send lidar and IMU (LEGACY, 48 B) to port 7502.
  const std::size_t fusa_128 = non_legacy_lidar_bytes(128, 8);
  const std::size_t legacy_64 = legacy_lidar_bytes(64);
  ASSERT_EQ(fusa_128, 16640u);
  ASSERT_EQ(legacy_64, 12608u);

  PcapReader reader(test::data_path("ouster/pcaps/same_ports.pcap"));
  const auto seen = read_all(reader);
  const std::uint32_t sensor_a = ip(169, 254, 238, 111);  // the 64-beam LEGACY sensor
  const std::uint32_t sensor_b = ip(169, 254, 92, 158);   // the 128-beam FUSA sensor
  const std::uint32_t host = ip(169, 254, 100, 204);
  const std::vector<Seen> expected = {
      {ns(1718314861, 30005000), sensor_a, host, 51514, 7502, 0, kOusterLegacyImuBytes,
       0x65cee69d41ebfb91},
      {ns(1718314861, 35157000), sensor_b, host, 40063, 7502, 1, kOusterLegacyImuBytes,
       0x378c69badb9ccd14},
      {ns(1718314861, 35591000), sensor_a, host, 44474, 7502, 10, legacy_64, 0xe92bcbbe0e40eef1},
      {ns(1718314861, 65119000), sensor_b, host, 44156, 7502, 22, fusa_128, 0x644de0cd37b98e69},
  };
  EXPECT_EQ(seen, expected);
  const auto& s = reader.stats();
  EXPECT_EQ(s.records, 23u);
  EXPECT_EQ(s.udp_datagrams, 4u);
  EXPECT_EQ(s.fragments, 21u);  // 9 + 12 fragments
  EXPECT_EQ(s.reassembled, 2u);
  EXPECT_EQ(s.incomplete_fragments, 0u);
  EXPECT_EQ(s.malformed, 0u);
  EXPECT_EQ(s.non_udp, 0u);
  EXPECT_EQ(s.min_record_time_ns, ns(1718314861, 30005000));
  EXPECT_EQ(s.max_record_time_ns, ns(1718314861, 65119000));
  EXPECT_TRUE(reader.end_error().empty());
  EXPECT_FALSE(reader.is_pcapng());
  EXPECT_EQ(reader.link_type_name(), "EN10MB");
}

TEST(PcapReader, OusterSamePortsLegacyAndNonLegacy) {
  {
    // same_ports_legacy.{1,2}.json: 128 px LEGACY and 64 px LEGACY, no IMU packet captured.
    PcapReader reader(test::data_path("ouster/pcaps/same_ports_legacy.pcap"));
    const auto seen = read_all(reader);
    ASSERT_EQ(seen.size(), 2u);
    EXPECT_EQ(seen[0].size, legacy_lidar_bytes(64));
    EXPECT_EQ(seen[0].hash, 0x3dc31a490db5bf2du);
    EXPECT_EQ(seen[1].size, legacy_lidar_bytes(128));
    EXPECT_EQ(seen[1].size, 24896u);
    EXPECT_EQ(seen[1].hash, 0x8cb8790e91575376u);
    for (const auto& d : seen) EXPECT_EQ(d.dst_port, 7502);
    EXPECT_EQ(reader.stats().fragments, 26u);
    EXPECT_EQ(reader.stats().reassembled, 2u);
    EXPECT_EQ(reader.stats().incomplete_fragments, 0u);
    EXPECT_EQ(reader.stats().malformed, 0u);
  }
  {
    // same_ports_nonlegacy: 128 px FUSA_RNG15_RFL8_NIR8_DUAL and 64 px RNG19_RFL8_SIG16_NIR16_DUAL
    // (16 B/px) are both 16640 B: size alone cannot tell the sensors apart (the source can).
    ASSERT_EQ(non_legacy_lidar_bytes(64, 16), 16640u);
    PcapReader reader(test::data_path("ouster/pcaps/same_ports_nonlegacy.pcap"));
    const auto seen = read_all(reader);
    ASSERT_EQ(seen.size(), 4u);
    const std::vector<std::size_t> sizes = {seen[0].size, seen[1].size, seen[2].size, seen[3].size};
    EXPECT_EQ(sizes, (std::vector<std::size_t>{48, 16640, 16640, 48}));
    EXPECT_EQ(seen[1].src_ip, ip(169, 254, 238, 111));
    EXPECT_EQ(seen[1].hash, 0xd06b358b852fa090u);
    EXPECT_EQ(seen[2].src_ip, ip(169, 254, 92, 158));
    EXPECT_EQ(seen[2].hash, 0x083912e8b93724dcu);
    EXPECT_EQ(seen[3].hash, 0xaf29a0f36b5af7c9u);
    EXPECT_EQ(reader.stats().fragments, 24u);
    EXPECT_EQ(reader.stats().reassembled, 2u);
    EXPECT_EQ(reader.stats().incomplete_fragments, 0u);
    EXPECT_EQ(reader.stats().malformed, 0u);
  }
}

TEST(PcapReader, OusterStaleFragmentWithReusedIdTimesOut) {
  // duplicate_id.pcap: one fragment with IP id 0x54db, then 88 s later a complete 6-fragment
  // datagram reusing that id. The stale set must expire, not poison the new one.
  PcapReader reader(test::data_path("ouster/pcaps/duplicate_id.pcap"));
  const auto seen = read_all(reader);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].size, 8448u);
  EXPECT_EQ(seen[0].dst_port, 34636);
  EXPECT_EQ(reader.stats().fragments, 7u);
  EXPECT_EQ(reader.stats().reassembled, 1u);
  EXPECT_EQ(reader.stats().incomplete_fragments, 1u);
  EXPECT_EQ(reader.reassembly_stats().timed_out, 1u);
  EXPECT_EQ(reader.stats().malformed, 0u);
}

TEST(PcapReader, OusterSeparatePorts) {
  PcapReader reader(test::data_path("ouster/pcaps/OS-1-64_1024x10_fw20.pcap"));
  std::size_t lidar = 0;
  std::size_t imu = 0;
  while (auto d = reader.next()) {
    if (d->dst_port == 7502 && d->payload.size() == legacy_lidar_bytes(64)) ++lidar;
    if (d->dst_port == 7503 && d->payload.size() == kOusterLegacyImuBytes) ++imu;
  }
  EXPECT_EQ(lidar, 64u);
  EXPECT_EQ(imu, 11u);
  EXPECT_EQ(reader.stats().udp_datagrams, 75u);
}

struct VelodyneCounts {
  std::size_t data = 0;
  std::size_t position = 0;
  std::size_t other = 0;
};

VelodyneCounts count_velodyne(PcapReader& reader) {
  VelodyneCounts c;
  while (auto d = reader.next()) {
    if (d->dst_port == 2368 && d->payload.size() == 1206) {
      ++c.data;
    } else if (d->dst_port == 8308 && d->payload.size() == 512) {
      ++c.position;
    } else {
      ++c.other;
    }
  }
  return c;
}

TEST(PcapReader, VelodyneHdl32CountsAndTimeSpan) {
  PcapReader reader(test::data_path("velodyne/veloview/monterey-first-100-packets.pcap"));
  const auto c = count_velodyne(reader);
  EXPECT_EQ(c.data, 2702u);
  EXPECT_EQ(c.position, 299u);
  EXPECT_EQ(c.other, 0u);
  const auto& s = reader.stats();
  EXPECT_EQ(s.records, 3001u);
  EXPECT_EQ(s.malformed, 0u);
  EXPECT_EQ(s.ip_length_clamped, 0u);
  // Microsecond capture: record times are whole microseconds.
  EXPECT_EQ(s.min_record_time_ns, ns(1355263594, 123168000));
  EXPECT_EQ(s.max_record_time_ns, ns(1355263595, 616799000));
}

TEST(PcapReader, VelodyneVlp16CountsDespiteWrongIpLengthInPositionPackets) {
  PcapReader reader(test::data_path("velodyne/veloview/vlp-16-test-90deg-1-50-frames.pcap"));
  const auto c = count_velodyne(reader);
  EXPECT_EQ(c.data, 1902u);
  EXPECT_EQ(c.position, 367u);
  EXPECT_EQ(c.other, 0u);
  // Every position packet of this firmware claims an IPv4 total length of 1234 for 540 bytes.
  EXPECT_EQ(reader.stats().ip_length_clamped, 367u);
  EXPECT_EQ(reader.stats().malformed, 0u);
}

TEST(PcapReader, NanosecondCaptureKeepsNanoseconds) {
  PcapReader reader(test::data_path("velodyne/nebula_vlp16/velodyne_vlp16.pcap"));
  const auto first = reader.next();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->capture_time_ns, ns(1673400471, 737763166));
  EXPECT_EQ(first->dst_port, 2368);
  std::size_t count = 1;
  while (reader.next()) ++count;
  EXPECT_EQ(count, 603u);
  EXPECT_EQ(reader.stats().max_record_time_ns, ns(1673400472, 137216567));
}

TEST(PcapReader, PortFilter) {
  PcapReader reader(test::data_path("velodyne/veloview/monterey-first-100-packets.pcap"));
  reader.set_port_filter({8308});
  const auto c = count_velodyne(reader);
  EXPECT_EQ(c.data, 0u);
  EXPECT_EQ(c.position, 299u);
  EXPECT_EQ(reader.stats().filtered, 2702u);

  // Fragmented datagrams are filtered after reassembly (only the first fragment has the port).
  PcapReader ouster(test::data_path("ouster/pcaps/same_ports.pcap"));
  ouster.set_port_filter({7503, 2368});
  EXPECT_TRUE(read_all(ouster).empty());
  EXPECT_EQ(ouster.stats().filtered, 4u);
  EXPECT_EQ(ouster.stats().reassembled, 2u);
  ouster.rewind();
  ouster.set_port_filter({7502});
  EXPECT_EQ(read_all(ouster).size(), 4u);
}

TEST(PcapReader, RewindAndMemoryInputGiveTheSameDatagrams) {
  const auto path = test::data_path("ouster/pcaps/same_ports.pcap");
  PcapReader reader(path);
  const auto first = read_all(reader);
  reader.rewind();
  const auto second = read_all(reader);
  EXPECT_EQ(first, second);
  EXPECT_EQ(reader.stats().records, 46u);  // stats accumulate across rewinds
  EXPECT_EQ(reader.stats().udp_datagrams, 8u);

  const Bytes bytes = read_file(path);
  auto memory = PcapReader::from_memory(bytes, "same_ports in memory");
  EXPECT_EQ(read_all(memory), first);
  memory.rewind();
  EXPECT_EQ(read_all(memory), first);
}

TEST(PcapReader, EmptyCaptureGivesNothingCleanly) {
  PcapReader reader(test::data_path("ouster/pcaps/empty_pcap.pcap"));
  EXPECT_FALSE(reader.next().has_value());
  EXPECT_FALSE(reader.next().has_value());  // stays at the end
  EXPECT_EQ(reader.stats().records, 0u);
  EXPECT_EQ(reader.stats().malformed, 0u);
  EXPECT_TRUE(reader.end_error().empty());
}

TEST(PcapReader, TruncatedFileEndsCleanlyAndCountsMalformed) {
  const Bytes original = read_file(test::data_path("ouster/pcaps/same_ports.pcap"));
  const RawPcap parsed = parse_pcap(original);
  ASSERT_EQ(parsed.records.size(), 23u);
  const auto dir = test::temp_dir("pcap-truncated");

  // Cut inside the data of record 20 (a fragment of the 16640-byte datagram, records 11..22).
  {
    const std::size_t cut = parsed.records[20].file_offset + 16 + 100;
    const fs::path path = dir / "cut_in_data.pcap";
    write_file(path, Bytes(original.begin(), original.begin() + static_cast<std::ptrdiff_t>(cut)));
    PcapReader reader(path);
    std::vector<Seen> seen;
    ASSERT_NO_THROW(seen = read_all(reader));
    ASSERT_EQ(seen.size(), 3u);
    EXPECT_EQ(seen[2].size, 12608u);
    EXPECT_EQ(reader.stats().records, 20u);
    EXPECT_EQ(reader.stats().malformed, 1u);
    EXPECT_EQ(reader.stats().incomplete_fragments, 1u);
    EXPECT_NE(reader.end_error().find("truncated"), std::string::npos) << reader.end_error();
    EXPECT_FALSE(reader.next().has_value());
  }
  // Cut inside the header of record 5 (the 12608-byte set, records 2..10, is left incomplete).
  {
    const std::size_t cut = parsed.records[5].file_offset + 7;
    const fs::path path = dir / "cut_in_header.pcap";
    write_file(path, Bytes(original.begin(), original.begin() + static_cast<std::ptrdiff_t>(cut)));
    PcapReader reader(path);
    const auto seen = read_all(reader);
    EXPECT_EQ(seen.size(), 2u);
    EXPECT_EQ(reader.stats().records, 5u);
    EXPECT_EQ(reader.stats().malformed, 1u);
    EXPECT_EQ(reader.stats().incomplete_fragments, 1u);
    EXPECT_FALSE(reader.end_error().empty());
  }
}

TEST(PcapReader, NonCaptureFilesThrow) {
  const auto dir = test::temp_dir("pcap-garbage");
  std::mt19937 rng(7);
  Bytes garbage(4096);
  for (auto& b : garbage) b = static_cast<std::byte>(rng() & 0xFF);
  write_file(dir / "garbage.bin", garbage);
  const std::string text = "(1436509052.249713) can0 123#DEADBEEF\n";
  Bytes text_bytes(text.size());
  std::memcpy(text_bytes.data(), text.data(), text.size());
  write_file(dir / "candump.log", text_bytes);
  write_file(dir / "empty.pcap", {});

  for (const char* name : {"garbage.bin", "candump.log", "empty.pcap"}) {
    try {
      PcapReader reader(dir / name);
      ADD_FAILURE() << name << " was accepted as a capture";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_EQ(e.offset(), 0u) << e.what();
    }
  }
  EXPECT_THROW(PcapReader(dir / "does-not-exist.pcap"), Error);
  EXPECT_THROW(PcapReader::from_memory(garbage), FormatError);
  EXPECT_THROW(PcapReader::from_memory({}), FormatError);
  // A pcap file header with an unknown major version.
  Bytes bad_version = read_file(test::data_path("ouster/pcaps/empty_pcap.pcap"));
  bad_version[4] = std::byte{9};
  EXPECT_THROW(PcapReader::from_memory(bad_version), FormatError);
}

// ---------------------------------------------------------------------------------------------
// Link types and pcapng (re-encoded real captures)

class PcapLinkTypes : public ::testing::TestWithParam<Link> {};

TEST_P(PcapLinkTypes, SameDatagramsAsEthernet) {
  const auto dir = test::temp_dir("pcap-links");
  for (const char* capture :
       {"ouster/pcaps/same_ports.pcap", "velodyne/veloview/monterey-first-100-packets.pcap"}) {
    const auto path = test::data_path(capture);
    const auto expected = read_all(path);
    ASSERT_FALSE(expected.empty());
    const RawPcap relinked = relink(parse_pcap(read_file(path)), GetParam());
    const fs::path out = dir / "relinked.pcap";
    write_file(out, serialize_pcap(relinked));
    PcapReader reader(out);
    EXPECT_EQ(read_all(reader), expected) << capture;
    EXPECT_EQ(reader.stats().malformed, 0u);
    EXPECT_EQ(reader.stats().non_udp, 0u);
  }
}

std::string link_test_name(const ::testing::TestParamInfo<Link>& param_info) {
  static constexpr std::array<const char*, 8> kNames = {"vlan", "qinq", "sll", "sll2",
                                                        "null", "loop", "raw", "ipv4"};
  return kNames[static_cast<std::size_t>(param_info.param)];
}

INSTANTIATE_TEST_SUITE_P(AllLinkTypes, PcapLinkTypes,
                         ::testing::Values(Link::vlan, Link::qinq, Link::sll, Link::sll2,
                                           Link::null_le, Link::loop, Link::raw, Link::ipv4),
                         link_test_name);

TEST(PcapReader, LinkTypeNames) {
  const RawPcap base = parse_pcap(read_file(test::data_path("ouster/pcaps/same_ports.pcap")));
  const auto dir = test::temp_dir("pcap-link-names");
  const std::vector<std::pair<Link, std::string>> names = {
      {Link::sll, "LINUX_SLL"}, {Link::sll2, "LINUX_SLL2"}, {Link::null_le, "NULL"},
      {Link::loop, "LOOP"},     {Link::raw, "RAW"},         {Link::ipv4, "IPV4"}};
  for (const auto& [link, name] : names) {
    write_file(dir / "x.pcap", serialize_pcap(relink(base, link)));
    EXPECT_EQ(PcapReader(dir / "x.pcap").link_type_name(), name);
  }
}

TEST(PcapReader, PcapngGivesTheSameDatagrams) {
  const auto dir = test::temp_dir("pcapng");
  for (const char* capture :
       {"ouster/pcaps/same_ports_nonlegacy.pcap", "velodyne/nebula_vlp16/velodyne_vlp16.pcap",
        "velodyne/veloview/vlp-16-test-90deg-1-50-frames.pcap"}) {
    const auto path = test::data_path(capture);
    const auto expected = read_all(path);
    const RawPcap parsed = parse_pcap(read_file(path));
    write_file(dir / "x.pcapng", serialize_pcapng(parsed));
    PcapReader reader(dir / "x.pcapng");
    EXPECT_TRUE(reader.is_pcapng());
    EXPECT_EQ(read_all(reader), expected) << capture;
    EXPECT_EQ(reader.stats().records, parsed.records.size());

    // The same with SLL2 inside pcapng.
    write_file(dir / "y.pcapng", serialize_pcapng(relink(parsed, Link::sll2)));
    EXPECT_EQ(read_all(dir / "y.pcapng"), expected) << capture;
  }
}

TEST(PcapReader, TruncatedPcapngEndsCleanly) {
  const RawPcap parsed =
      parse_pcap(read_file(test::data_path("ouster/pcaps/same_ports_nonlegacy.pcap")));
  const Bytes ng = serialize_pcapng(parsed);
  // Drop the last 30 bytes: the final enhanced packet block (the 48-byte IMU datagram) is cut.
  const auto dir = test::temp_dir("pcapng-cut");
  write_file(dir / "cut.pcapng", Bytes(ng.begin(), ng.end() - 30));
  PcapReader reader(dir / "cut.pcapng");
  EXPECT_EQ(read_all(reader).size(), 3u);
  EXPECT_EQ(reader.stats().malformed, 1u);
  EXPECT_FALSE(reader.end_error().empty());
}

// ---------------------------------------------------------------------------------------------
// Malformed and foreign records

TEST(PcapReader, MalformedAndForeignRecordsAreCountedAndSkipped) {
  const auto dir = test::temp_dir("pcap-malformed");
  // A valid 100-byte datagram as a template frame.
  Bytes payload(100);
  std::iota(reinterpret_cast<std::uint8_t*>(payload.data()),
            reinterpret_cast<std::uint8_t*>(payload.data()) + payload.size(), std::uint8_t{1});
  {
    PcapWriter writer(dir / "template.pcap");
    writer.write_udp(ns(1700000000, 0), ip(10, 0, 0, 2), 1000, ip(10, 0, 0, 1), 2000, payload);
  }
  RawPcap pcap = parse_pcap(read_file(dir / "template.pcap"));
  ASSERT_EQ(pcap.records.size(), 1u);
  const RawRecord good = pcap.records[0];
  const std::size_t ip_at = 14;
  auto variant = [&](auto&& mutate) {
    RawRecord r = good;
    mutate(r);
    return r;
  };
  pcap.records = {
      variant([](RawRecord& r) { r.data.resize(10); }),  // shorter than an Ethernet header
      variant([&](RawRecord& r) { r.data[ip_at] = std::byte{0x44}; }),  // IHL 4
      variant([&](RawRecord& r) { r.data[ip_at] = std::byte{0x65}; }),  // IP version 6
      variant([&](RawRecord& r) {
        r.data[ip_at + 2] = std::byte{0};
        r.data[ip_at + 3] = std::byte{10};
      }),  // total < IHL
      variant(
          [&](RawRecord& r) { r.data[ip_at + 20 + 4] = std::byte{0x7F}; }),  // UDP length too big
      variant([&](RawRecord& r) {
        r.data[ip_at + 20 + 4] = std::byte{0};
        r.data[ip_at + 20 + 5] = std::byte{4};
      }),                                                // UDP length < 8
      variant([](RawRecord& r) { r.data.resize(60); }),  // snaplen cut: IP length > captured
      variant([&](RawRecord& r) {                        // 9 stacked VLAN tags: beyond the bound
        Bytes tagged(r.data.begin(), r.data.begin() + 12);
        for (int i = 0; i < 9; ++i) append_be(tagged, 0x81000001, 4);  // TPID + VLAN 1
        tagged.insert(tagged.end(), r.data.begin() + 12, r.data.end());
        r.data = tagged;
        r.original_length = static_cast<std::uint32_t>(tagged.size());
      }),
      variant([&](RawRecord& r) {
        r.data[12] = std::byte{0x08};
        r.data[13] = std::byte{0x06};
      }),  // ARP
      variant([&](RawRecord& r) {
        r.data[12] = std::byte{0x86};
        r.data[13] = std::byte{0xDD};
      }),                                                                // IPv6
      variant([&](RawRecord& r) { r.data[ip_at + 9] = std::byte{6}; }),  // TCP
      variant([&](RawRecord& r) {  // wrong (too large) IP length on a complete frame: tolerated
        r.data[ip_at + 2] = std::byte{0x04};
        r.data[ip_at + 3] = std::byte{0xD2};
      }),
      good,
  };
  write_file(dir / "mixed.pcap", serialize_pcap(pcap));
  PcapReader reader(dir / "mixed.pcap");
  const auto seen = read_all(reader);
  ASSERT_EQ(seen.size(), 2u);
  for (const auto& d : seen) {
    EXPECT_EQ(d.size, 100u);
    EXPECT_EQ(d.hash, fnv1a64(payload));
  }
  EXPECT_EQ(seen[0].record_index, 11u);
  EXPECT_EQ(seen[1].record_index, 12u);
  const auto& s = reader.stats();
  EXPECT_EQ(s.records, 13u);
  EXPECT_EQ(s.malformed, 8u);
  EXPECT_EQ(s.non_udp, 3u);
  EXPECT_EQ(s.ip_length_clamped, 1u);
  EXPECT_TRUE(reader.end_error().empty());
}

TEST(PcapReader, UnsupportedLinkTypeCountsEverythingAsNonUdp) {
  RawPcap pcap = parse_pcap(read_file(test::data_path("ouster/pcaps/same_ports.pcap")));
  pcap.link_type = 147;  // LINKTYPE_USER0
  const auto dir = test::temp_dir("pcap-user0");
  write_file(dir / "user0.pcap", serialize_pcap(pcap));
  PcapReader reader(dir / "user0.pcap");
  EXPECT_TRUE(read_all(reader).empty());
  EXPECT_EQ(reader.stats().non_udp, 23u);
  EXPECT_EQ(reader.stats().malformed, 0u);
}

// ---------------------------------------------------------------------------------------------
// Writer

Bytes pattern_payload(std::size_t size, std::uint32_t seed) {
  Bytes out(size);
  std::mt19937 rng(seed);
  for (auto& b : out) b = static_cast<std::byte>(rng() & 0xFF);
  return out;
}

struct Sent {
  std::int64_t time_ns;
  std::uint32_t src_ip;
  std::uint16_t src_port;
  std::uint32_t dst_ip;
  std::uint16_t dst_port;
  Bytes payload;
};

std::vector<Sent> sample_datagrams() {
  // Sizes around every boundary for a 1500-byte MTU (1472 = largest unfragmented UDP payload).
  const std::vector<std::size_t> sizes = {0,    1,    7,    18,   48,    1206,  1472,
                                          1473, 2952, 2953, 8448, 16640, 24896, 65507};
  std::vector<Sent> out;
  std::int64_t t = ns(1718314861, 123456789);
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    out.push_back({t, ip(169, 254, 238, 111), static_cast<std::uint16_t>(40000 + i),
                   i % 3 == 0 ? ip(239, 255, 0, 1) : ip(169, 254, 100, 204),
                   static_cast<std::uint16_t>(i % 2 == 0 ? 7502 : 7503),
                   pattern_payload(sizes[i], static_cast<std::uint32_t>(i))});
    t += 1'234'567;
  }
  return out;
}

std::vector<Seen> expected_seen(const std::vector<Sent>& sent, const RawPcap& written) {
  // record_index = index of the last record of each datagram, found from the MF flag.
  std::vector<std::uint64_t> last_records;
  for (std::size_t i = 0; i < written.records.size(); ++i) {
    if ((get_be16(written.records[i].data, 14 + 6) & 0x2000) == 0) last_records.push_back(i);
  }
  std::vector<Seen> out;
  for (std::size_t i = 0; i < sent.size(); ++i) {
    const auto& s = sent[i];
    out.push_back({s.time_ns, s.src_ip, s.dst_ip, s.src_port, s.dst_port, last_records.at(i),
                   s.payload.size(), fnv1a64(s.payload)});
  }
  return out;
}

TEST(PcapWriter, RoundTripWithFragmentationAndCorrectHeaders) {
  const auto dir = test::temp_dir("pcap-writer");
  const auto sent = sample_datagrams();
  {
    PcapWriter writer(dir / "out.pcap");
    for (const auto& s : sent) {
      writer.write_udp(s.time_ns, s.src_ip, s.src_port, s.dst_ip, s.dst_port, s.payload);
    }
    writer.flush();
  }
  const RawPcap written = parse_pcap(read_file(dir / "out.pcap"));
  EXPECT_TRUE(written.nanosecond);
  EXPECT_EQ(written.link_type, 1u);

  // Independent checks of every record: Ethernet/IPv4 framing, header checksum, fragment shape.
  std::size_t fragments = 0;
  std::size_t expected_fragments = 0;
  for (const auto& s : sent) {
    const std::size_t udp_bytes = s.payload.size() + 8;
    if (udp_bytes > 1480) expected_fragments += (udp_bytes + 1479) / 1480;
  }
  for (const auto& r : written.records) {
    ASSERT_GE(r.data.size(), 60u);
    EXPECT_EQ(r.original_length, r.data.size());
    EXPECT_EQ(get_be16(r.data, 12), 0x0800);
    const std::span<const std::byte> header(r.data.data() + 14, 20);
    EXPECT_EQ(std::to_integer<int>(header[0]), 0x45);
    EXPECT_EQ(ones_complement_sum(header), 0xFFFF) << "IPv4 header checksum";
    const std::size_t total = get_be16(r.data, 14 + 2);
    EXPECT_LE(total, 1500u);
    EXPECT_LE(14 + total, r.data.size());
    const std::uint16_t flags = get_be16(r.data, 14 + 6);
    if ((flags & 0x3FFF) != 0) {
      ++fragments;
      if ((flags & 0x2000) != 0) {
        EXPECT_EQ((total - 20) % 8, 0u);
      }
    } else {
      // Unfragmented: the UDP checksum over the pseudo-header must verify.
      Bytes pseudo(r.data.begin() + 14 + 12, r.data.begin() + 14 + 20);
      append_be(pseudo, 17, 2);
      append_be(pseudo, total - 20, 2);
      pseudo.insert(pseudo.end(), r.data.begin() + 34,
                    r.data.begin() + 14 + static_cast<std::ptrdiff_t>(total));
      EXPECT_EQ(ones_complement_sum(pseudo), 0xFFFF) << "UDP checksum";
    }
  }
  EXPECT_EQ(fragments, expected_fragments);
  // Multicast destinations get the RFC 1112 MAC 01:00:5e:7f:00:01 for 239.255.0.1.
  EXPECT_EQ(std::to_integer<int>(written.records[0].data[0]), 0x01);
  EXPECT_EQ(std::to_integer<int>(written.records[0].data[2]), 0x5E);
  EXPECT_EQ(std::to_integer<int>(written.records[0].data[3]), 0x7F);

  PcapReader reader(dir / "out.pcap");
  EXPECT_EQ(read_all(reader), expected_seen(sent, written));
  EXPECT_EQ(reader.stats().fragments, expected_fragments);
  EXPECT_EQ(reader.stats().malformed, 0u);
  EXPECT_EQ(reader.stats().incomplete_fragments, 0u);
}

TEST(PcapWriter, OutOfOrderDuplicatedAndInterleavedFragments) {
  const auto dir = test::temp_dir("pcap-reorder");
  const auto sent = sample_datagrams();
  {
    PcapWriter writer(dir / "in_order.pcap");
    for (const auto& s : sent) {
      writer.write_udp(s.time_ns, s.src_ip, s.src_port, s.dst_ip, s.dst_port, s.payload);
    }
  }
  const RawPcap in_order = parse_pcap(read_file(dir / "in_order.pcap"));
  const auto expected = read_all(dir / "in_order.pcap");

  // Group records per datagram (IP identification), then: reverse the 16640-byte datagram,
  // shuffle the 65507-byte one, interleave the 8448 and 24896 ones, duplicate one fragment.
  std::vector<std::vector<RawRecord>> groups;
  std::uint16_t last_id = 0;
  for (const auto& r : in_order.records) {
    const std::uint16_t id = get_be16(r.data, 14 + 4);
    if (groups.empty() || id != last_id) groups.emplace_back();
    groups.back().push_back(r);
    last_id = id;
  }
  ASSERT_EQ(groups.size(), sent.size());
  std::reverse(groups[11].begin(), groups[11].end());
  std::shuffle(groups[13].begin(), groups[13].end(), std::mt19937(3));
  const RawRecord duplicate = groups[13][0];
  groups[13].insert(groups[13].begin() + 1, duplicate);  // an exact duplicate before completion
  std::vector<RawRecord> interleaved;
  for (std::size_t i = 0; i < std::max(groups[10].size(), groups[12].size()); ++i) {
    if (i < groups[12].size()) interleaved.push_back(groups[12][groups[12].size() - 1 - i]);
    if (i < groups[10].size()) interleaved.push_back(groups[10][i]);
  }
  groups[10] = interleaved;
  groups[12].clear();

  RawPcap shuffled = in_order;
  shuffled.records.clear();
  for (const auto& g : groups) shuffled.records.insert(shuffled.records.end(), g.begin(), g.end());
  write_file(dir / "shuffled.pcap", serialize_pcap(shuffled));

  PcapReader reader(dir / "shuffled.pcap");
  auto seen = read_all(reader);
  // Completion order and completing records changed (every fragment record still carries its
  // datagram's time); compare everything else.
  std::sort(seen.begin(), seen.end(), [](auto& a, auto& b) { return a.src_port < b.src_port; });
  ASSERT_EQ(seen.size(), expected.size());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    Seen a = seen[i];
    Seen b = expected[i];
    a.record_index = b.record_index = 0;
    EXPECT_EQ(a, b) << "datagram " << i;
  }
  EXPECT_EQ(reader.reassembly_stats().duplicates, 1u);
  EXPECT_EQ(reader.stats().malformed, 0u);
  EXPECT_EQ(reader.stats().incomplete_fragments, 0u);

  // A "duplicate" with different bytes is an overlap conflict: that datagram is dropped.
  RawPcap conflicting = shuffled;
  const std::size_t duplicate_index = shuffled.records.size() - groups[13].size() + 1;
  conflicting.records[duplicate_index].data.back() ^= std::byte{0xFF};
  write_file(dir / "conflict.pcap", serialize_pcap(conflicting));
  PcapReader conflict_reader(dir / "conflict.pcap");
  const auto after_conflict = read_all(conflict_reader);
  EXPECT_EQ(after_conflict.size(), sent.size() - 1);
  EXPECT_EQ(conflict_reader.reassembly_stats().conflicts, 1u);
  EXPECT_EQ(conflict_reader.stats().malformed, 1u);
  EXPECT_EQ(conflict_reader.stats().incomplete_fragments, 1u);  // the rest of the discarded set
  for (const auto& d : after_conflict) EXPECT_NE(d.size, 65507u);
}

TEST(PcapWriter, MicrosecondResolutionSmallMtuAndLimits) {
  const auto dir = test::temp_dir("pcap-writer-us");
  const Bytes payload = pattern_payload(3000, 9);
  {
    PcapWriter writer(dir / "us.pcap", {.nanosecond_resolution = false, .mtu = 576});
    writer.write_udp(ns(1600000000, 999'999'999), ip(10, 1, 2, 3), 5, ip(255, 255, 255, 255), 6,
                     payload);
    EXPECT_THROW(writer.write_udp(0, 1, 2, 3, 4, pattern_payload(65508, 1)), std::invalid_argument);
    EXPECT_THROW(writer.write_udp(-1, 1, 2, 3, 4, payload), std::invalid_argument);
  }
  EXPECT_THROW(PcapWriter(dir / "bad.pcap", {.nanosecond_resolution = true, .mtu = 40}),
               std::invalid_argument);
  EXPECT_THROW(PcapWriter(dir / "no-such-dir" / "x.pcap"), Error);

  const RawPcap written = parse_pcap(read_file(dir / "us.pcap"));
  EXPECT_FALSE(written.nanosecond);
  // 3008 UDP bytes in 552-byte chunks (576 - 20, rounded down to a multiple of 8): 6 fragments.
  ASSERT_EQ(written.records.size(), 6u);
  for (const auto& r : written.records) {
    EXPECT_LE(get_be16(r.data, 14 + 2), 576);
    EXPECT_EQ(std::to_integer<int>(r.data[0]), 0xFF);  // broadcast MAC
  }
  PcapReader reader(dir / "us.pcap");
  const auto d = reader.next();
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->capture_time_ns, ns(1600000000, 999'999'000));  // truncated to microseconds
  EXPECT_EQ(fnv1a64(d->payload), fnv1a64(payload));
  EXPECT_FALSE(reader.next().has_value());
}

// ---------------------------------------------------------------------------------------------
// Ipv4Reassembler on its own

struct FragmentPlan {
  std::uint32_t offset;
  std::size_t length;
  bool more;
};

std::vector<FragmentPlan> split(std::size_t total, std::size_t chunk) {
  std::vector<FragmentPlan> out;
  for (std::size_t off = 0; off < total; off += chunk) {
    const std::size_t len = std::min(chunk, total - off);
    out.push_back({static_cast<std::uint32_t>(off), len, off + len < total});
  }
  return out;
}

Ipv4Fragment fragment_of(const Ipv4FragmentKey& key, const Bytes& datagram, const FragmentPlan& p) {
  return {key, p.offset, p.more, std::span<const std::byte>(datagram.data() + p.offset, p.length)};
}

TEST(Ipv4Reassembler, RandomOrdersAndDuplicatesReassembleExactly) {
  std::mt19937 rng(12345);
  Ipv4Reassembler reassembler;
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t total = 9 + rng() % 30000;
    const std::size_t chunk = 8 * (1 + rng() % 400);
    const Bytes datagram = pattern_payload(total, static_cast<std::uint32_t>(trial));
    auto plan = split(total, chunk);
    if (plan.size() < 2) continue;
    std::shuffle(plan.begin(), plan.end(), rng);
    if (trial % 3 == 0) {
      const FragmentPlan duplicate = plan[0];
      plan.insert(plan.begin() + 1, duplicate);  // a duplicate before completion
    }
    const Ipv4FragmentKey key{ip(10, 0, 0, 1), ip(10, 0, 0, 2), static_cast<std::uint16_t>(trial),
                              17};
    std::size_t completions = 0;
    for (std::size_t i = 0; i < plan.size(); ++i) {
      const auto result = reassembler.add(fragment_of(key, datagram, plan[i]), trial);
      if (result.status == Ipv4Reassembler::Status::complete) {
        ++completions;
        ASSERT_EQ(i, plan.size() - 1);
        ASSERT_EQ(result.datagram.size(), total);
        ASSERT_EQ(std::memcmp(result.datagram.data(), datagram.data(), total), 0);
      } else {
        ASSERT_TRUE(result.status == Ipv4Reassembler::Status::pending ||
                    result.status == Ipv4Reassembler::Status::duplicate);
      }
    }
    ASSERT_EQ(completions, 1u) << "trial " << trial;
  }
  EXPECT_EQ(reassembler.stats().conflicts, 0u);
  EXPECT_EQ(reassembler.stats().invalid, 0u);
  EXPECT_EQ(reassembler.pending_sets(), 0u);
}

TEST(Ipv4Reassembler, InterleavedSetsWithTheSameIdButDifferentKeys) {
  Ipv4Reassembler reassembler;
  const Bytes a = pattern_payload(3000, 1);
  const Bytes b = pattern_payload(2000, 2);
  const Ipv4FragmentKey key_a{1, 2, 77, 17};
  const Ipv4FragmentKey key_b{3, 2, 77, 17};  // same id, other source
  const auto plan_a = split(a.size(), 1480);
  const auto plan_b = split(b.size(), 1480);
  EXPECT_EQ(reassembler.add(fragment_of(key_a, a, plan_a[0]), 0).status,
            Ipv4Reassembler::Status::pending);
  EXPECT_EQ(reassembler.add(fragment_of(key_b, b, plan_b[1]), 0).status,
            Ipv4Reassembler::Status::pending);
  EXPECT_EQ(reassembler.add(fragment_of(key_a, a, plan_a[2]), 0).status,
            Ipv4Reassembler::Status::pending);
  EXPECT_EQ(reassembler.pending_sets(), 2u);
  auto rb = reassembler.add(fragment_of(key_b, b, plan_b[0]), 0);
  ASSERT_EQ(rb.status, Ipv4Reassembler::Status::complete);
  EXPECT_EQ(std::memcmp(rb.datagram.data(), b.data(), b.size()), 0);
  auto ra = reassembler.add(fragment_of(key_a, a, plan_a[1]), 0);
  ASSERT_EQ(ra.status, Ipv4Reassembler::Status::complete);
  EXPECT_EQ(std::memcmp(ra.datagram.data(), a.data(), a.size()), 0);
}

TEST(Ipv4Reassembler, ConflictsDiscardTheSet) {
  const Bytes d = pattern_payload(4000, 5);
  const Ipv4FragmentKey key{1, 2, 3, 17};
  using S = Ipv4Reassembler::Status;
  auto frag = [&](std::uint32_t off, std::size_t len, bool more) {
    return Ipv4Fragment{key, off, more, std::span<const std::byte>(d.data() + off, len)};
  };
  {  // partial overlap (teardrop style: the second fragment starts inside the first)
    Ipv4Reassembler r;
    EXPECT_EQ(r.add(frag(0, 1480, true), 0).status, S::pending);
    EXPECT_EQ(r.add(frag(1472, 1480, true), 0).status, S::conflict);
    EXPECT_EQ(r.pending_sets(), 0u);
    EXPECT_EQ(r.stats().conflicts, 1u);
  }
  {  // same range, different bytes
    Ipv4Reassembler r;
    Bytes other = d;
    other[10] ^= std::byte{1};
    EXPECT_EQ(r.add(frag(0, 1480, true), 0).status, S::pending);
    EXPECT_EQ(r.add({key, 0, true, std::span<const std::byte>(other.data(), 1480)}, 0).status,
              S::conflict);
  }
  {  // two last fragments that disagree on the total length
    Ipv4Reassembler r;
    EXPECT_EQ(r.add(frag(1480, 100, false), 0).status, S::pending);
    EXPECT_EQ(r.add(frag(1480, 200, false), 0).status, S::conflict);
  }
  {  // data beyond the announced end
    Ipv4Reassembler r;
    EXPECT_EQ(r.add(frag(1480, 100, false), 0).status, S::pending);
    EXPECT_EQ(r.add(frag(1584, 8, true), 0).status, S::conflict);
  }
  {  // the end announced below data already received
    Ipv4Reassembler r;
    EXPECT_EQ(r.add(frag(2960, 16, true), 0).status, S::pending);
    EXPECT_EQ(r.add(frag(1480, 100, false), 0).status, S::conflict);
  }
  {  // a repeat of part of a fragment with the same bytes is harmless
    Ipv4Reassembler r;
    EXPECT_EQ(r.add(frag(0, 1480, true), 0).status, S::pending);
    EXPECT_EQ(r.add(frag(8, 8, true), 0).status, S::duplicate);
    EXPECT_EQ(r.stats().duplicates, 1u);
  }
  {  // after a conflict the key starts afresh and can complete
    Ipv4Reassembler r;
    Bytes other = d;
    other[9] ^= std::byte{1};
    EXPECT_EQ(r.add(frag(0, 1480, true), 0).status, S::pending);
    EXPECT_EQ(r.add({key, 8, true, std::span<const std::byte>(other.data() + 8, 8)}, 0).status,
              S::conflict);
    EXPECT_EQ(r.add(frag(1480, 1480, true), 0).status, S::pending);
    EXPECT_EQ(r.add(frag(2960, 1040, false), 0).status, S::pending);
    const auto done = r.add(frag(0, 1480, true), 0);
    ASSERT_EQ(done.status, S::complete);
    EXPECT_EQ(done.datagram.size(), 4000u);
  }
}

TEST(Ipv4Reassembler, InvalidFragmentsAreRejected) {
  const Bytes d = pattern_payload(70000, 6);
  Ipv4Reassembler r;
  const Ipv4FragmentKey key{1, 2, 3, 17};
  using S = Ipv4Reassembler::Status;
  auto add = [&](std::uint32_t off, std::size_t len, bool more) {
    return r.add({key, off, more, std::span<const std::byte>(d.data(), len)}, 0).status;
  };
  EXPECT_EQ(add(0, 1479, true), S::invalid);     // non-last fragment not a multiple of 8
  EXPECT_EQ(add(0, 0, true), S::invalid);        // empty non-last fragment
  EXPECT_EQ(add(0, 100, false), S::invalid);     // not a fragment at all
  EXPECT_EQ(add(65528, 16, false), S::invalid);  // ends beyond 65515 bytes ("ping of death")
  EXPECT_EQ(add(12, 8, true), S::invalid);       // offset not a multiple of 8
  EXPECT_EQ(r.stats().invalid, 5u);
  EXPECT_EQ(r.pending_sets(), 0u);
  EXPECT_EQ(add(65512, 3, false), S::pending);  // 65515 exactly is allowed
}

TEST(Ipv4Reassembler, TimeoutEvictionAndFlushBoundMemory) {
  const Bytes d = pattern_payload(3000, 8);
  Ipv4ReassemblyLimits limits;
  limits.max_pending_sets = 4;
  limits.timeout_ns = 1'000'000'000;
  Ipv4Reassembler r(limits);
  auto first_half = [&](std::uint16_t id) {
    return Ipv4Fragment{{1, 2, id, 17}, 0, true, std::span<const std::byte>(d.data(), 1480)};
  };
  // 1000 sets that never complete: the table never exceeds 4 sets.
  for (std::uint16_t id = 0; id < 1000; ++id) {
    EXPECT_EQ(r.add(first_half(id), 0).status, Ipv4Reassembler::Status::pending);
    ASSERT_LE(r.pending_sets(), 4u);
  }
  EXPECT_EQ(r.stats().evicted, 996u);
  // The least recently touched set went first: ids 996..999 remain; touching 996 keeps it over
  // the next eviction.
  EXPECT_EQ(r.add({{1, 2, 996, 17}, 1480, true, std::span<const std::byte>(d.data(), 8)}, 0).status,
            Ipv4Reassembler::Status::pending);
  EXPECT_EQ(r.add(first_half(5000), 0).status, Ipv4Reassembler::Status::pending);
  const auto done =
      r.add({{1, 2, 996, 17}, 1488, false, std::span<const std::byte>(d.data() + 1488, 1512)}, 0);
  EXPECT_EQ(done.status, Ipv4Reassembler::Status::complete);

  EXPECT_EQ(r.stats().evicted, 997u);  // 997 (not 996) went when 5000 arrived

  // Timeout: sets further than timeout_ns from now, in either direction, expire.
  Ipv4Reassembler t(limits);
  EXPECT_EQ(t.add(first_half(1), 0).status, Ipv4Reassembler::Status::pending);
  EXPECT_EQ(t.add(first_half(2), 500'000'000).status, Ipv4Reassembler::Status::pending);
  t.expire(1'000'000'000);  // set 1 exactly at the timeout: kept
  EXPECT_EQ(t.stats().timed_out, 0u);
  t.expire(1'000'000'001);
  EXPECT_EQ(t.stats().timed_out, 1u);
  EXPECT_EQ(t.pending_sets(), 1u);
  // The capture clock jumps back 5 s: set 2 is now 5.5 s away and expires too.
  EXPECT_EQ(t.add(first_half(3), -5'000'000'000).status, Ipv4Reassembler::Status::pending);
  EXPECT_EQ(t.stats().timed_out, 2u);
  EXPECT_EQ(t.pending_sets(), 1u);
  t.flush();
  EXPECT_EQ(t.stats().flushed, 1u);
  EXPECT_EQ(t.stats().incomplete(), 3u);
  EXPECT_EQ(t.pending_sets(), 0u);
}

}  // namespace
}  // namespace livod::io

// ---------------------------------------------------------------------------------------------
// Reading past damage (issue 14): the reader resumes after a corrupt record and says what it lost.

namespace livod::io {
namespace {

std::vector<Seen> without_indices(std::vector<Seen> seen) {
  for (auto& s : seen) s.record_index = 0;
  return seen;
}

void put_le32(Bytes& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<std::byte>((v >> (8 * i)) & 0xFF);
}

TEST(PcapDamage, ReadsPastACorruptCaptureLengthAndReportsTheLoss) {
  const fs::path capture = test::data_path("velodyne/veloview/vlp-16-test-90deg-1-50-frames.pcap");
  Bytes bytes = read_file(capture);
  const RawPcap parsed = parse_pcap(bytes);
  ASSERT_GT(parsed.records.size(), 1100u);
  std::vector<Seen> expected = without_indices(read_all(capture));
  ASSERT_EQ(expected.size(), parsed.records.size());
  const std::size_t damaged = 1000;
  expected.erase(expected.begin() + static_cast<std::ptrdiff_t>(damaged));
  const RawRecord& record = parsed.records[damaged];
  put_le32(bytes, record.file_offset + 8, 0xFFFFFFFF);  // the capture length of the issue

  PcapReader reader = PcapReader::from_memory(bytes, "damaged.pcap");
  EXPECT_EQ(without_indices(read_all(reader)), expected);
  EXPECT_TRUE(reader.end_error().empty()) << reader.end_error();
  ASSERT_EQ(reader.losses().count(), 1u);
  const InputLoss& loss = reader.losses().entries()[0];
  EXPECT_EQ(loss.file, "damaged.pcap");
  EXPECT_EQ(loss.byte_offset, record.file_offset);
  EXPECT_EQ(loss.bytes, 16 + record.data.size());
  EXPECT_EQ(loss.records, 1u);
  EXPECT_TRUE(loss.records_estimated);
  ASSERT_TRUE(loss.seconds.has_value());
  const auto time_of = [&](std::size_t i) {
    return static_cast<double>(parsed.records[i].seconds) +
           1e-6 * static_cast<double>(parsed.records[i].fraction);
  };
  EXPECT_NEAR(*loss.seconds, time_of(damaged + 1) - time_of(damaged - 1), 2e-6);
  const std::string text = format_loss(loss);
  EXPECT_NE(text.find("damaged.pcap: at byte offset " + std::to_string(record.file_offset)),
            std::string::npos)
      << text;
  EXPECT_EQ(reader.stats().malformed, 1u);
}

TEST(PcapDamage, ReadsPastGarbageBetweenRecords) {
  const fs::path capture = test::data_path("velodyne/veloview/vlp-16-test-90deg-1-50-frames.pcap");
  Bytes bytes = read_file(capture);
  const RawPcap parsed = parse_pcap(bytes);
  const std::vector<Seen> expected = without_indices(read_all(capture));
  std::mt19937 rng(14);
  Bytes garbage(5000);
  for (auto& b : garbage) b = static_cast<std::byte>(rng() & 0xFF);
  const std::size_t at = parsed.records[500].file_offset;
  bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(at), garbage.begin(), garbage.end());

  PcapReader reader = PcapReader::from_memory(bytes, "garbage.pcap");
  EXPECT_EQ(without_indices(read_all(reader)), expected);
  ASSERT_EQ(reader.losses().count(), 1u);
  EXPECT_EQ(reader.losses().entries()[0].byte_offset, at);
  EXPECT_EQ(reader.losses().entries()[0].bytes, garbage.size());
}

TEST(PcapDamage, ReadsPastABrokenPcapngBlock) {
  const RawPcap parsed =
      parse_pcap(read_file(test::data_path("velodyne/nebula_vlp16/velodyne_vlp16.pcap")));
  Bytes ng = serialize_pcapng(parsed);
  PcapReader intact = PcapReader::from_memory(ng, "intact.pcapng");
  std::vector<Seen> expected = without_indices(read_all(intact));
  ASSERT_GT(expected.size(), 100u);
  // Walk the blocks to the 50th enhanced packet block and break its total length.
  std::size_t at = 0;
  std::size_t epb = 0;
  while (true) {
    const std::uint32_t type = get_le32(ng, at);
    const std::uint32_t length = get_le32(ng, at + 4);
    if (type == 6 && epb++ == 50) break;
    at += length;
  }
  const std::uint32_t length = get_le32(ng, at + 4);
  put_le32(ng, at + 4, 0x00FFFF00);
  expected.erase(expected.begin() + 50);

  PcapReader reader = PcapReader::from_memory(ng, "broken.pcapng");
  EXPECT_EQ(without_indices(read_all(reader)), expected);
  ASSERT_EQ(reader.losses().count(), 1u);
  EXPECT_EQ(reader.losses().entries()[0].byte_offset, at);
  EXPECT_EQ(reader.losses().entries()[0].bytes, length);
}

TEST(PcapDamage, TruncationIsALossToTheEndOfTheFile) {
  const Bytes original = read_file(test::data_path("ouster/pcaps/same_ports.pcap"));
  const RawPcap parsed = parse_pcap(original);
  const std::size_t cut = parsed.records[20].file_offset + 16 + 100;
  PcapReader reader = PcapReader::from_memory(
      Bytes(original.begin(), original.begin() + static_cast<std::ptrdiff_t>(cut)), "cut.pcap");
  read_all(reader);
  ASSERT_EQ(reader.losses().count(), 1u);
  const InputLoss& loss = reader.losses().entries()[0];
  EXPECT_EQ(loss.byte_offset, parsed.records[20].file_offset);
  EXPECT_EQ(loss.bytes, 116u);
  EXPECT_FALSE(loss.seconds.has_value());
  EXPECT_NE(loss.reason.find("the file ends in the damage"), std::string::npos) << loss.reason;
  EXPECT_FALSE(reader.end_error().empty());
}

TEST(PcapDamage, IntactCapturesReportNoLoss) {
  PcapReader reader(test::data_path("velodyne/nebula_vlp16/velodyne_vlp16.pcap"));
  read_all(reader);
  EXPECT_TRUE(reader.losses().empty());
}

}  // namespace
}  // namespace livod::io
