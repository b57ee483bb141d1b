#pragma once
// Livox SDK2 control protocol (Mid-360, HAP): 24-byte header, CRC-16/CCITT-FALSE over the header,
// CRC-32 over the data, key-value parameter commands (sensor-protocols.md 2.1, 2.2).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace livod::livox::sdk2 {

inline constexpr std::size_t kHeaderBytes = 24;
inline constexpr std::uint16_t kDiscoveryPort = 56000;

namespace cmd {
inline constexpr std::uint16_t kDiscovery = 0x0000;
inline constexpr std::uint16_t kSetParams = 0x0100;
inline constexpr std::uint16_t kQueryParams = 0x0101;
inline constexpr std::uint16_t kPushStatus = 0x0102;
inline constexpr std::uint16_t kReboot = 0x0200;
}  // namespace cmd

namespace key {
inline constexpr std::uint16_t kPclDataType = 0x0000;
inline constexpr std::uint16_t kPatternMode = 0x0001;
inline constexpr std::uint16_t kStateDestination = 0x0005;
inline constexpr std::uint16_t kPointDestination = 0x0006;
inline constexpr std::uint16_t kImuDestination = 0x0007;
inline constexpr std::uint16_t kWorkMode = 0x001A;
inline constexpr std::uint16_t kImuDataEnable = 0x001C;
inline constexpr std::uint16_t kCurrentWorkState = 0x8006;
}  // namespace key

enum class WorkMode : std::uint8_t { kSampling = 0x01, kIdle = 0x02, kReady = 0x09 };

struct ControlFrame {
  std::uint32_t seq = 0;
  std::uint16_t cmd_id = 0;
  std::uint8_t cmd_type = 0;     // 0 REQ, 1 ACK
  std::uint8_t sender_type = 0;  // 0 host, 1 LiDAR
  std::vector<std::byte> data;
};

enum class ParseError { kNone, kTooShort, kBadSof, kBadLength, kBadHeaderCrc, kBadDataCrc };
const char* to_string(ParseError e);

std::vector<std::byte> encode(const ControlFrame& frame);
ParseError parse(std::span<const std::byte> data, ControlFrame& out);

struct KeyValue {
  std::uint16_t key = 0;
  std::vector<std::byte> value;
};

ControlFrame discovery(std::uint32_t seq);
ControlFrame set_params(std::uint32_t seq, const std::vector<KeyValue>& params);
ControlFrame set_work_mode(std::uint32_t seq, WorkMode mode);
// Destination value: dst_ip[4] (dotted-quad order), dst_port u16, src_port u16.
KeyValue destination(std::uint16_t key, std::uint32_t host_ip, std::uint16_t host_port,
                     std::uint16_t lidar_port);

struct DiscoveryAck {
  std::uint8_t ret = 0;
  std::uint8_t device_type = 0;  // 9 Mid-360, 10 industrial HAP, 15 HAP, 35 Mid-360s
  std::string serial;
  std::uint32_t lidar_ip = 0;  // host order
  std::uint16_t cmd_port = 0;
};
bool parse_discovery_ack(const ControlFrame& f, DiscoveryAck& out);

struct SetParamsAck {
  std::uint8_t ret = 0;
  std::uint16_t error_key = 0;
};
bool parse_set_params_ack(const ControlFrame& f, SetParamsAck& out);

}  // namespace livod::livox::sdk2
