#include "drivers/livox/sdk2_control.hpp"

#include "drivers/livox/bytes.hpp"
#include "drivers/livox/crc.hpp"

namespace livod::livox::sdk2 {
namespace {
constexpr std::byte kSof{0xAA};
constexpr std::size_t kMaxFrame = 1400;
}  // namespace

const char* to_string(ParseError e) {
  switch (e) {
    case ParseError::kNone:
      return "ok";
    case ParseError::kTooShort:
      return "frame shorter than its 24-byte header";
    case ParseError::kBadSof:
      return "start-of-frame byte is not 0xAA";
    case ParseError::kBadLength:
      return "length field inconsistent with the datagram";
    case ParseError::kBadHeaderCrc:
      return "header CRC-16 mismatch";
    case ParseError::kBadDataCrc:
      return "data CRC-32 mismatch";
  }
  return "unknown";
}

std::vector<std::byte> encode(const ControlFrame& f) {
  std::vector<std::byte> out;
  out.reserve(kHeaderBytes + f.data.size());
  out.push_back(kSof);
  out.push_back(std::byte{0});
  append_le<std::uint16_t>(out, static_cast<std::uint16_t>(kHeaderBytes + f.data.size()));
  append_le<std::uint32_t>(out, f.seq);
  append_le<std::uint16_t>(out, f.cmd_id);
  out.push_back(static_cast<std::byte>(f.cmd_type));
  out.push_back(static_cast<std::byte>(f.sender_type));
  out.insert(out.end(), 6, std::byte{0});
  append_le<std::uint16_t>(out, crc16_ccitt_false(std::span(out).first(18)));
  append_le<std::uint32_t>(out, f.data.empty() ? 0U : crc32_standard(f.data));
  out.insert(out.end(), f.data.begin(), f.data.end());
  return out;
}

ParseError parse(std::span<const std::byte> data, ControlFrame& out) {
  if (data.size() < kHeaderBytes) return ParseError::kTooShort;
  if (data[0] != kSof) return ParseError::kBadSof;
  const auto length = read_le<std::uint16_t>(data, 2);
  if (length < kHeaderBytes || length > data.size() || length > kMaxFrame) {
    return ParseError::kBadLength;
  }
  if (crc16_ccitt_false(data.first(18)) != read_le<std::uint16_t>(data, 18)) {
    return ParseError::kBadHeaderCrc;
  }
  const auto body = data.subspan(kHeaderBytes, length - kHeaderBytes);
  const auto crc = read_le<std::uint32_t>(data, 20);
  if (!body.empty() && crc32_standard(body) != crc) return ParseError::kBadDataCrc;
  out.seq = read_le<std::uint32_t>(data, 4);
  out.cmd_id = read_le<std::uint16_t>(data, 8);
  out.cmd_type = static_cast<std::uint8_t>(data[10]);
  out.sender_type = static_cast<std::uint8_t>(data[11]);
  out.data.assign(body.begin(), body.end());
  return ParseError::kNone;
}

ControlFrame discovery(std::uint32_t seq) {
  return ControlFrame{seq, cmd::kDiscovery, 0, 0, {}};
}

ControlFrame set_params(std::uint32_t seq, const std::vector<KeyValue>& params) {
  ControlFrame f{seq, cmd::kSetParams, 0, 0, {}};
  append_le<std::uint16_t>(f.data, static_cast<std::uint16_t>(params.size()));
  append_le<std::uint16_t>(f.data, 0);
  for (const auto& kv : params) {
    append_le<std::uint16_t>(f.data, kv.key);
    append_le<std::uint16_t>(f.data, static_cast<std::uint16_t>(kv.value.size()));
    f.data.insert(f.data.end(), kv.value.begin(), kv.value.end());
  }
  return f;
}

ControlFrame set_work_mode(std::uint32_t seq, WorkMode mode) {
  return set_params(seq, {KeyValue{key::kWorkMode, {static_cast<std::byte>(mode)}}});
}

KeyValue destination(std::uint16_t k, std::uint32_t host_ip, std::uint16_t host_port,
                     std::uint16_t lidar_port) {
  KeyValue kv{k, {}};
  for (int shift = 24; shift >= 0; shift -= 8) {
    kv.value.push_back(static_cast<std::byte>((host_ip >> shift) & 0xFF));
  }
  append_le(kv.value, host_port);
  append_le(kv.value, lidar_port);
  return kv;
}

bool parse_discovery_ack(const ControlFrame& f, DiscoveryAck& out) {
  if (f.cmd_id != cmd::kDiscovery || f.cmd_type != 1 || f.data.size() < 24) return false;
  const std::span<const std::byte> d(f.data);
  out.ret = static_cast<std::uint8_t>(d[0]);
  out.device_type = static_cast<std::uint8_t>(d[1]);
  out.serial.clear();
  for (std::size_t i = 2; i < 18 && d[i] != std::byte{0}; ++i) {
    out.serial.push_back(static_cast<char>(d[i]));
  }
  out.lidar_ip = (static_cast<std::uint32_t>(d[18]) << 24) |
                 (static_cast<std::uint32_t>(d[19]) << 16) |
                 (static_cast<std::uint32_t>(d[20]) << 8) | static_cast<std::uint32_t>(d[21]);
  out.cmd_port = read_le<std::uint16_t>(d, 22);
  return true;
}

bool parse_set_params_ack(const ControlFrame& f, SetParamsAck& out) {
  if (f.cmd_id != cmd::kSetParams || f.cmd_type != 1 || f.data.size() < 3) return false;
  out.ret = static_cast<std::uint8_t>(f.data[0]);
  out.error_key = read_le<std::uint16_t>(std::span<const std::byte>(f.data), 1);
  return true;
}

}  // namespace livod::livox::sdk2
