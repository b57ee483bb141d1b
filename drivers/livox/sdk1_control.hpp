#pragma once
// Livox SDK1 control protocol (Avia, Horizon, Mid-40/70, Tele-15): frame layout, CRCs and the
// commands livod needs for bring-up (sensor-protocols.md 1.1, 1.2). Frames are built and parsed
// here; sockets and timing live in the device state machine.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace livod::livox::sdk1 {

enum class PacketType : std::uint8_t { kCmd = 0, kAck = 1, kMsg = 2 };

enum class CmdSet : std::uint8_t { kGeneral = 0, kLidar = 1, kHub = 2 };

// General (cmd_set 0) and LiDAR (cmd_set 1) command ids used by livod.
namespace cmd {
inline constexpr std::uint8_t kBroadcast = 0x00;
inline constexpr std::uint8_t kHandshake = 0x01;
inline constexpr std::uint8_t kHeartbeat = 0x03;
inline constexpr std::uint8_t kSampling = 0x04;
inline constexpr std::uint8_t kCoordinate = 0x05;
inline constexpr std::uint8_t kDisconnect = 0x06;
inline constexpr std::uint8_t kAbnormalPush = 0x07;
inline constexpr std::uint8_t kReturnMode = 0x06;  // cmd_set 1
inline constexpr std::uint8_t kImuRate = 0x08;     // cmd_set 1
inline constexpr std::uint8_t kUtcSync = 0x0A;     // cmd_set 1
}  // namespace cmd

inline constexpr std::uint16_t kBroadcastPort = 55000;
inline constexpr std::uint16_t kLidarCommandPort = 65000;
inline constexpr std::size_t kFrameOverhead = 15;  // header (11) + crc32 (4)

struct ControlFrame {
  PacketType type = PacketType::kCmd;
  std::uint16_t seq = 0;
  std::uint8_t cmd_set = 0;
  std::uint8_t cmd_id = 0;
  std::vector<std::byte> payload;
};

enum class ParseError { kNone, kTooShort, kBadSof, kBadLength, kBadHeaderCrc, kBadFrameCrc };
const char* to_string(ParseError e);

std::vector<std::byte> encode(const ControlFrame& frame);
// Parses one frame from the start of `data`. `out.payload` is resized (control traffic is rare;
// the data path never calls this).
ParseError parse(std::span<const std::byte> data, ControlFrame& out);

// Command builders.
ControlFrame heartbeat(std::uint16_t seq);
ControlFrame sampling(std::uint16_t seq, bool start);
// Livox-SDK sends the handshake with packet_type ACK (a documented quirk); livod does the same.
ControlFrame handshake(std::uint16_t seq, std::uint32_t host_ip, std::uint16_t data_port,
                       std::uint16_t cmd_port, std::uint16_t sensor_port);
ControlFrame coordinate_system(std::uint16_t seq, bool spherical);
ControlFrame return_mode(std::uint16_t seq, std::uint8_t mode);  // 0 first .. 3 triple
ControlFrame imu_rate(std::uint16_t seq, bool enable_200hz);
ControlFrame disconnect(std::uint16_t seq);

struct BroadcastInfo {
  std::string broadcast_code;  // 15 ASCII characters (serial number based)
  std::uint8_t device_type = 0;
};
// A broadcast MSG (cmd_set 0, cmd_id 0) from a LiDAR; false if `frame` is not one.
bool parse_broadcast(const ControlFrame& frame, BroadcastInfo& out);

struct HeartbeatAck {
  std::uint8_t ret_code = 0;
  std::uint8_t state = 0;
  std::uint8_t feature = 0;
  std::uint32_t status = 0;  // LidarErrorCode bitfield
};
bool parse_heartbeat_ack(const ControlFrame& frame, HeartbeatAck& out);
// ret_code of a generic ACK (first payload byte); false when the payload is empty.
bool ack_return_code(const ControlFrame& frame, std::uint8_t& ret_code);

}  // namespace livod::livox::sdk1
