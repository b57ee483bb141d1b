#include "io/pcap_records.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/time.hpp"
#include "io/packet_headers.hpp"

namespace livod::io {
namespace {

constexpr std::uint32_t kMagicMicro = 0xA1B2C3D4;
constexpr std::uint32_t kMagicNano = 0xA1B23C4D;
constexpr std::uint32_t kSnaplen = 262144;  // libpcap's MAXIMUM_SNAPLEN
constexpr std::uint32_t kLinkEthernet = 1;  // DLT_EN10MB
constexpr std::size_t kIpv4Header = 20;
constexpr std::size_t kMaxUdpPayload = 65535 - kIpv4Header - kUdpHeader;
constexpr std::size_t kMinEthernetFrame = 60;  // without FCS; shorter frames are padded
constexpr std::size_t kMinIpv4Mtu = 68;        // RFC 791: every host must accept this
constexpr std::size_t kMaxIpv4Mtu = 65535;

void put16(std::byte* out, std::uint16_t v) {
  out[0] = static_cast<std::byte>(v >> 8);
  out[1] = static_cast<std::byte>(v & 0xFF);
}

void put32(std::byte* out, std::uint32_t v) {
  put16(out, static_cast<std::uint16_t>(v >> 16));
  put16(out + 2, static_cast<std::uint16_t>(v & 0xFFFF));
}

// Host byte order, as libpcap writes its headers.
void put_host32(std::byte* out, std::uint32_t v) {
  std::memcpy(out, &v, sizeof(v));
}

void put_host16(std::byte* out, std::uint16_t v) {
  std::memcpy(out, &v, sizeof(v));
}

std::uint16_t be16(const std::byte* b) {
  return static_cast<std::uint16_t>((std::to_integer<unsigned>(b[0]) << 8) |
                                    std::to_integer<unsigned>(b[1]));
}

// Internet checksum (RFC 1071) accumulation over big-endian 16-bit words.
std::uint32_t checksum_add(std::uint32_t sum, std::span<const std::byte> bytes) {
  std::size_t i = 0;
  for (; i + 1 < bytes.size(); i += 2) sum += be16(bytes.data() + i);
  if (i < bytes.size()) sum += std::to_integer<std::uint32_t>(bytes[i]) << 8;
  return sum;
}

std::uint16_t checksum_finish(std::uint32_t sum) {
  while ((sum >> 16) != 0) sum = (sum & 0xFFFF) + (sum >> 16);
  return static_cast<std::uint16_t>(~sum & 0xFFFF);
}

void mac_for_ip(std::byte* mac, std::uint32_t ip) {
  if ((ip >> 28) == 0xE) {  // 224.0.0.0/4: RFC 1112 multicast MAC 01:00:5e + low 23 bits
    const std::uint32_t low = ip & 0x7FFFFF;
    mac[0] = std::byte{0x01};
    mac[1] = std::byte{0x00};
    mac[2] = std::byte{0x5E};
    mac[3] = static_cast<std::byte>(low >> 16);
    mac[4] = static_cast<std::byte>((low >> 8) & 0xFF);
    mac[5] = static_cast<std::byte>(low & 0xFF);
  } else if (ip == 0xFFFFFFFF) {
    std::memset(mac, 0xFF, 6);
  } else {  // locally administered unicast MAC derived from the address
    mac[0] = std::byte{0x02};
    mac[1] = std::byte{0x00};
    put32(mac + 2, ip);
  }
}

}  // namespace

std::array<std::byte, kPcapFileHeaderBytes> pcap_file_header(bool nanosecond_resolution) {
  std::array<std::byte, kPcapFileHeaderBytes> h{};
  put_host32(h.data(), nanosecond_resolution ? kMagicNano : kMagicMicro);
  put_host16(h.data() + 4, 2);  // version 2.4
  put_host16(h.data() + 6, 4);
  // thiszone and sigfigs stay 0
  put_host32(h.data() + 16, kSnaplen);
  put_host32(h.data() + 20, kLinkEthernet);
  return h;
}

UdpPcapEncoder::UdpPcapEncoder(PcapRecordFormat format) : format_(format) {
  if (format.mtu < kMinIpv4Mtu || format.mtu > kMaxIpv4Mtu) {
    throw std::invalid_argument("pcap writer: mtu " + std::to_string(format.mtu) +
                                " outside [68, 65535]");
  }
}

std::size_t UdpPcapEncoder::record_bytes(std::size_t payload_bytes) const {
  const std::size_t udp_length = kUdpHeader + payload_bytes;
  const std::size_t max_chunk = ((format_.mtu - kIpv4Header) / 8) * 8;
  std::size_t total = 0;
  for (std::size_t offset = 0; offset < udp_length; offset += max_chunk) {
    const std::size_t chunk = std::min(max_chunk, udp_length - offset);
    total +=
        kPcapRecordHeaderBytes + std::max(kEthernetHeader + kIpv4Header + chunk, kMinEthernetFrame);
  }
  return total;
}

void UdpPcapEncoder::append(std::vector<std::byte>& out, std::int64_t capture_time_ns,
                            std::uint32_t src_ip, std::uint16_t src_port, std::uint32_t dst_ip,
                            std::uint16_t dst_port, std::span<const std::byte> payload) {
  if (payload.size() > kMaxUdpPayload) {
    throw std::invalid_argument("pcap writer: UDP payload of " + std::to_string(payload.size()) +
                                " bytes exceeds 65507");
  }
  const std::int64_t seconds = capture_time_ns / kNsPerSecond;
  const std::int64_t sub_second_ns = capture_time_ns % kNsPerSecond;
  if (capture_time_ns < 0 || seconds > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("pcap writer: time " + std::to_string(capture_time_ns) +
                                " ns does not fit a pcap record");
  }

  // UDP header + payload, checksummed over the RFC 768 pseudo-header.
  const std::size_t udp_length = kUdpHeader + payload.size();
  udp_.resize(udp_length);
  std::byte* udp = udp_.data();
  put16(udp, src_port);
  put16(udp + 2, dst_port);
  put16(udp + 4, static_cast<std::uint16_t>(udp_length));
  put16(udp + 6, 0);
  if (!payload.empty()) std::memcpy(udp + kUdpHeader, payload.data(), payload.size());
  std::byte pseudo[12];
  put32(pseudo, src_ip);
  put32(pseudo + 4, dst_ip);
  pseudo[8] = std::byte{0};
  pseudo[9] = std::byte{kIpProtoUdp};
  put16(pseudo + 10, static_cast<std::uint16_t>(udp_length));
  std::uint16_t udp_checksum = checksum_finish(checksum_add(checksum_add(0, pseudo), udp_));
  if (udp_checksum == 0) udp_checksum = 0xFFFF;  // 0 means "no checksum" in UDP over IPv4
  put16(udp + 6, udp_checksum);

  const auto fraction = static_cast<std::uint32_t>(
      format_.nanosecond_resolution ? sub_second_ns : sub_second_ns / 1000);
  // Every fragment but the last carries a multiple of 8 bytes (the offset unit).
  const std::size_t max_chunk = ((format_.mtu - kIpv4Header) / 8) * 8;
  const std::uint16_t ip_id = next_ip_id_++;
  for (std::size_t offset = 0; offset < udp_length; offset += max_chunk) {
    const std::size_t chunk = std::min(max_chunk, udp_length - offset);
    const bool more = offset + chunk < udp_length;
    const std::size_t ip_length = kIpv4Header + chunk;
    const std::size_t frame_length = std::max(kEthernetHeader + ip_length, kMinEthernetFrame);
    const std::size_t at = out.size();
    out.resize(at + kPcapRecordHeaderBytes + frame_length, std::byte{0});
    std::byte* record = out.data() + at;
    put_host32(record, static_cast<std::uint32_t>(seconds));
    put_host32(record + 4, fraction);
    put_host32(record + 8, static_cast<std::uint32_t>(frame_length));
    put_host32(record + 12, static_cast<std::uint32_t>(frame_length));

    std::byte* eth = record + kPcapRecordHeaderBytes;
    std::memset(eth, 0, frame_length);
    mac_for_ip(eth, dst_ip);
    mac_for_ip(eth + 6, src_ip);
    put16(eth + 12, kEthertypeIpv4);

    std::byte* ip = eth + kEthernetHeader;
    ip[0] = std::byte{0x45};  // version 4, 5 header words
    ip[1] = std::byte{0};
    put16(ip + 2, static_cast<std::uint16_t>(ip_length));
    put16(ip + 4, ip_id);
    put16(ip + 6, static_cast<std::uint16_t>((more ? kIpMoreFragments : 0) | (offset / 8)));
    ip[8] = std::byte{64};  // TTL
    ip[9] = std::byte{kIpProtoUdp};
    put32(ip + 12, src_ip);
    put32(ip + 16, dst_ip);
    put16(ip + 10, checksum_finish(checksum_add(0, {ip, kIpv4Header})));
    std::memcpy(ip + kIpv4Header, udp_.data() + offset, chunk);
  }
}

}  // namespace livod::io
