#include "drivers/livox/sdk1_control.hpp"

#include "drivers/livox/bytes.hpp"
#include "drivers/livox/crc.hpp"

namespace livod::livox::sdk1 {
namespace {

constexpr std::byte kSof{0xAA};
constexpr std::size_t kHeaderBytes = 11;

ControlFrame command(std::uint16_t seq, CmdSet set, std::uint8_t id,
                     std::vector<std::byte> payload = {}) {
  return ControlFrame{PacketType::kCmd, seq, static_cast<std::uint8_t>(set), id,
                      std::move(payload)};
}

}  // namespace

const char* to_string(ParseError e) {
  switch (e) {
    case ParseError::kNone:
      return "ok";
    case ParseError::kTooShort:
      return "frame shorter than its header";
    case ParseError::kBadSof:
      return "start-of-frame byte is not 0xAA";
    case ParseError::kBadLength:
      return "length field inconsistent with the datagram";
    case ParseError::kBadHeaderCrc:
      return "header CRC-16 mismatch";
    case ParseError::kBadFrameCrc:
      return "frame CRC-32 mismatch";
  }
  return "unknown";
}

std::vector<std::byte> encode(const ControlFrame& f) {
  std::vector<std::byte> out;
  out.reserve(kFrameOverhead + f.payload.size());
  out.push_back(kSof);
  out.push_back(std::byte{0});  // version
  append_le<std::uint16_t>(out, static_cast<std::uint16_t>(kFrameOverhead + f.payload.size()));
  out.push_back(static_cast<std::byte>(f.type));
  append_le<std::uint16_t>(out, f.seq);
  append_le<std::uint16_t>(out, crc16_sdk1(std::span(out).first(7)));
  out.push_back(static_cast<std::byte>(f.cmd_set));
  out.push_back(static_cast<std::byte>(f.cmd_id));
  out.insert(out.end(), f.payload.begin(), f.payload.end());
  append_le<std::uint32_t>(out, crc32_sdk1(out));
  return out;
}

ParseError parse(std::span<const std::byte> data, ControlFrame& out) {
  if (data.size() < kFrameOverhead) return ParseError::kTooShort;
  if (data[0] != kSof) return ParseError::kBadSof;
  const auto length = read_le<std::uint16_t>(data, 2);
  if (length < kFrameOverhead || length > data.size()) return ParseError::kBadLength;
  if (crc16_sdk1(data.first(7)) != read_le<std::uint16_t>(data, 7)) {
    return ParseError::kBadHeaderCrc;
  }
  if (crc32_sdk1(data.first(length - 4U)) != read_le<std::uint32_t>(data, length - 4U)) {
    return ParseError::kBadFrameCrc;
  }
  out.type = static_cast<PacketType>(static_cast<std::uint8_t>(data[4]));
  out.seq = read_le<std::uint16_t>(data, 5);
  out.cmd_set = static_cast<std::uint8_t>(data[9]);
  out.cmd_id = static_cast<std::uint8_t>(data[10]);
  const auto payload = data.subspan(kHeaderBytes, length - kFrameOverhead);
  out.payload.assign(payload.begin(), payload.end());
  return ParseError::kNone;
}

ControlFrame heartbeat(std::uint16_t seq) {
  return command(seq, CmdSet::kGeneral, cmd::kHeartbeat);
}

ControlFrame sampling(std::uint16_t seq, bool start) {
  return command(seq, CmdSet::kGeneral, cmd::kSampling,
                 {std::byte{start ? std::uint8_t{1} : std::uint8_t{0}}});
}

ControlFrame handshake(std::uint16_t seq, std::uint32_t host_ip, std::uint16_t data_port,
                       std::uint16_t cmd_port, std::uint16_t sensor_port) {
  std::vector<std::byte> p;
  // The IP goes in network order, i.e. the dotted-quad bytes in order.
  for (int shift = 24; shift >= 0; shift -= 8) {
    p.push_back(static_cast<std::byte>((host_ip >> shift) & 0xFF));
  }
  append_le(p, data_port);
  append_le(p, cmd_port);
  append_le(p, sensor_port);
  ControlFrame f = command(seq, CmdSet::kGeneral, cmd::kHandshake, std::move(p));
  f.type = PacketType::kAck;
  return f;
}

ControlFrame coordinate_system(std::uint16_t seq, bool spherical) {
  return command(seq, CmdSet::kGeneral, cmd::kCoordinate,
                 {std::byte{spherical ? std::uint8_t{1} : std::uint8_t{0}}});
}

ControlFrame return_mode(std::uint16_t seq, std::uint8_t mode) {
  return command(seq, CmdSet::kLidar, cmd::kReturnMode, {std::byte{mode}});
}

ControlFrame imu_rate(std::uint16_t seq, bool enable_200hz) {
  return command(seq, CmdSet::kLidar, cmd::kImuRate,
                 {std::byte{enable_200hz ? std::uint8_t{1} : std::uint8_t{0}}});
}

ControlFrame disconnect(std::uint16_t seq) {
  return command(seq, CmdSet::kGeneral, cmd::kDisconnect);
}

bool parse_broadcast(const ControlFrame& f, BroadcastInfo& out) {
  if (f.type != PacketType::kMsg || f.cmd_set != 0 || f.cmd_id != cmd::kBroadcast) return false;
  if (f.payload.size() < 17) return false;
  out.broadcast_code.clear();
  for (std::size_t i = 0; i < 16 && f.payload[i] != std::byte{0}; ++i) {
    out.broadcast_code.push_back(static_cast<char>(f.payload[i]));
  }
  out.device_type = static_cast<std::uint8_t>(f.payload[16]);
  return true;
}

bool parse_heartbeat_ack(const ControlFrame& f, HeartbeatAck& out) {
  if (f.type != PacketType::kAck || f.cmd_set != 0 || f.cmd_id != cmd::kHeartbeat) return false;
  if (f.payload.size() < 7) return false;
  const std::span<const std::byte> p(f.payload);
  out.ret_code = static_cast<std::uint8_t>(p[0]);
  out.state = static_cast<std::uint8_t>(p[1]);
  out.feature = static_cast<std::uint8_t>(p[2]);
  out.status = read_le<std::uint32_t>(p, 3);
  return true;
}

bool ack_return_code(const ControlFrame& f, std::uint8_t& ret_code) {
  if (f.payload.empty()) return false;
  ret_code = static_cast<std::uint8_t>(f.payload[0]);
  return true;
}

}  // namespace livod::livox::sdk1
