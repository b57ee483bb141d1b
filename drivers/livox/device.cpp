#include "drivers/livox/device.hpp"

#include "drivers/livox/sdk1_control.hpp"
#include "drivers/livox/sdk2_control.hpp"

namespace livod::livox {
namespace {
constexpr std::uint32_t kBroadcastIp = 0xFFFFFFFFU;
constexpr std::uint16_t kSdk2LidarCmdPort = 56100;
}  // namespace

const char* to_string(DeviceState s) {
  switch (s) {
    case DeviceState::kDiscovering:
      return "DISCOVERING";
    case DeviceState::kConnecting:
      return "CONNECTING";
    case DeviceState::kStarting:
      return "STARTING";
    case DeviceState::kStreaming:
      return "STREAMING";
    case DeviceState::kStale:
      return "STALE";
  }
  return "?";
}

LivoxDevice::LivoxDevice(DeviceConfig config) : config_(std::move(config)) {
  lidar_ip_ = config_.lidar_ip;
  lidar_cmd_port_ =
      config_.protocol == Protocol::kSdk1 ? sdk1::kLidarCommandPort : kSdk2LidarCmdPort;
  state_ = lidar_ip_ ? DeviceState::kConnecting : DeviceState::kDiscovering;
}

void LivoxDevice::enter(DeviceState s, HostTime now) {
  if (s == DeviceState::kStale) ++counters_.stale_events;
  if (s == DeviceState::kStreaming) {
    if (streamed_before_) ++counters_.reconnects;
    streamed_before_ = true;
  }
  state_ = s;
  state_since_ = now;
  awaiting_ack_ = false;
  last_alive_ = now;
}

void LivoxDevice::send(std::vector<OutgoingFrame>& out, std::uint32_t ip, std::uint16_t port,
                       std::vector<std::byte> bytes, HostTime now) {
  out.push_back(OutgoingFrame{ip, port, std::move(bytes)});
  ++counters_.frames_sent;
  last_sent_ = now;
}

void LivoxDevice::on_data(HostTime now) {
  last_alive_ = now;
  // Data without an ACK means the LiDAR already streams to us (e.g. SDK2 factory defaults, or a
  // lost ACK): that is streaming.
  if (state_ == DeviceState::kStarting) enter(DeviceState::kStreaming, now);
}

void LivoxDevice::on_control_datagram(std::span<const std::byte> bytes, std::uint32_t src_ip,
                                      HostTime now) {
  if (config_.protocol == Protocol::kSdk1) {
    sdk1::ControlFrame f;
    if (sdk1::parse(bytes, f) != sdk1::ParseError::kNone) {
      ++counters_.bad_frames;
      return;
    }
    sdk1::BroadcastInfo info;
    if (sdk1::parse_broadcast(f, info)) {
      const bool ours =
          config_.broadcast_code.empty() || info.broadcast_code == config_.broadcast_code;
      if (ours && (state_ == DeviceState::kDiscovering || state_ == DeviceState::kStale)) {
        lidar_ip_ = src_ip;
        enter(DeviceState::kConnecting, now);
      }
      return;
    }
    if (f.type != sdk1::PacketType::kAck) return;
    ++counters_.acks;
    std::uint8_t ret = 0;
    sdk1::ack_return_code(f, ret);
    if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kHeartbeat) {
      sdk1::HeartbeatAck hb;
      if (sdk1::parse_heartbeat_ack(f, hb)) counters_.last_status = hb.status;
      last_alive_ = now;
      return;
    }
    if (ret != 0) {
      ++counters_.nacks;
      awaiting_ack_ = false;  // retried on the next tick
      return;
    }
    if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kHandshake && state_ == DeviceState::kConnecting) {
      enter(DeviceState::kStarting, now);
      last_heartbeat_ = now;
    } else if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kSampling &&
               state_ == DeviceState::kStarting) {
      enter(DeviceState::kStreaming, now);
    }
    return;
  }
  sdk2::ControlFrame f;
  if (sdk2::parse(bytes, f) != sdk2::ParseError::kNone) {
    ++counters_.bad_frames;
    return;
  }
  if (f.cmd_type != 1) {
    if (f.cmd_id == sdk2::cmd::kPushStatus) last_alive_ = now;
    return;
  }
  ++counters_.acks;
  sdk2::DiscoveryAck disc;
  if (sdk2::parse_discovery_ack(f, disc)) {
    if (state_ == DeviceState::kDiscovering || state_ == DeviceState::kStale) {
      lidar_ip_ = disc.lidar_ip != 0 ? disc.lidar_ip : src_ip;
      if (disc.cmd_port != 0) lidar_cmd_port_ = disc.cmd_port;
      enter(DeviceState::kConnecting, now);
    }
    return;
  }
  sdk2::SetParamsAck ack;
  if (sdk2::parse_set_params_ack(f, ack)) {
    if (ack.ret != 0) {
      ++counters_.nacks;
      awaiting_ack_ = false;
      return;
    }
    if (state_ == DeviceState::kConnecting)
      enter(DeviceState::kStarting, now);
    else if (state_ == DeviceState::kStarting)
      enter(DeviceState::kStreaming, now);
  }
}

void LivoxDevice::tick(HostTime now, std::vector<OutgoingFrame>& out) {
  const bool sdk1 = config_.protocol == Protocol::kSdk1;
  // Liveness: heartbeat ACKs (SDK1), status pushes or data keep the device alive.
  if ((state_ == DeviceState::kStreaming || state_ == DeviceState::kStarting) &&
      now - last_alive_ > config_.stale_after) {
    enter(DeviceState::kStale, now);
  }
  if (awaiting_ack_ && now - last_sent_ > config_.command_timeout) {
    ++counters_.timeouts;
    awaiting_ack_ = false;
  }
  switch (state_) {
    case DeviceState::kDiscovering:
    case DeviceState::kStale:
      if (!sdk1 && now - last_sent_ >= config_.discovery_period) {
        send(out, kBroadcastIp, sdk2::kDiscoveryPort, sdk2::encode(sdk2::discovery(seq_++)), now);
      }
      // A known address need not wait for a broadcast to reconnect.
      if (state_ == DeviceState::kStale && config_.lidar_ip) enter(DeviceState::kConnecting, now);
      break;
    case DeviceState::kConnecting:
      if (!awaiting_ack_ && lidar_ip_) {
        if (sdk1) {
          send(out, *lidar_ip_, lidar_cmd_port_,
               sdk1::encode(sdk1::handshake(static_cast<std::uint16_t>(seq_++), config_.host_ip,
                                            config_.host_data_port, config_.host_cmd_port,
                                            config_.host_imu_port)),
               now);
        } else {
          send(out, *lidar_ip_, lidar_cmd_port_,
               sdk2::encode(sdk2::set_params(
                   seq_++, {sdk2::destination(sdk2::key::kStateDestination, config_.host_ip,
                                              config_.host_state_port, 56200),
                            sdk2::destination(sdk2::key::kPointDestination, config_.host_ip,
                                              config_.host_data_port, 56300),
                            sdk2::destination(sdk2::key::kImuDestination, config_.host_ip,
                                              config_.host_imu_port, 56400)})),
               now);
        }
        awaiting_ack_ = true;
      }
      break;
    case DeviceState::kStarting:
      if (!awaiting_ack_ && lidar_ip_) {
        send(out, *lidar_ip_, lidar_cmd_port_,
             sdk1 ? sdk1::encode(sdk1::sampling(static_cast<std::uint16_t>(seq_++), true))
                  : sdk2::encode(sdk2::set_work_mode(seq_++, sdk2::WorkMode::kSampling)),
             now);
        awaiting_ack_ = true;
      }
      break;
    case DeviceState::kStreaming:
      break;
  }
  if (sdk1 && lidar_ip_ &&
      (state_ == DeviceState::kStarting || state_ == DeviceState::kStreaming) &&
      now - last_heartbeat_ >= config_.heartbeat_period) {
    send(out, *lidar_ip_, lidar_cmd_port_,
         sdk1::encode(sdk1::heartbeat(static_cast<std::uint16_t>(seq_++))), now);
    last_heartbeat_ = now;
  }
}

}  // namespace livod::livox
