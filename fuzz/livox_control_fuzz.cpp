// libFuzzer target: Livox control frames (SDK1 and SDK2 parsers and the reply parsers behind
// them) and the LivoxDevice bring-up state machine fed arbitrary datagrams.
//
// Input: byte 0 selects the mode, the rest is the data.
//   mode 0: sdk1::parse (+ broadcast / heartbeat-ACK / return-code parsers on a parsed frame)
//   mode 1: sdk2::parse (+ discovery-ACK / set-params-ACK parsers)
//   mode 2/3: a LivoxDevice (SDK1 / SDK2) fed a sequence of datagrams, each prefixed by a 2-byte
//           little-endian length and a 1-byte time step (x 10 ms); tick() runs after each one.
// Oracles beyond crashes and sanitizer reports: a frame that parses re-encodes into a frame that
// parses back to the same fields; every frame the device asks to send parses with its own
// protocol's parser; device counters never run backwards, and there is no reconnect without a
// STALE before it.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drivers/livox/device.hpp"
#include "drivers/livox/sdk1_control.hpp"
#include "drivers/livox/sdk2_control.hpp"

namespace {

namespace lx = livod::livox;

void fuzz_sdk1(std::span<const std::byte> data) {
  lx::sdk1::ControlFrame f;
  if (lx::sdk1::parse(data, f) != lx::sdk1::ParseError::kNone) return;
  lx::sdk1::BroadcastInfo info;
  (void)lx::sdk1::parse_broadcast(f, info);
  lx::sdk1::HeartbeatAck hb;
  (void)lx::sdk1::parse_heartbeat_ack(f, hb);
  std::uint8_t ret = 0;
  (void)lx::sdk1::ack_return_code(f, ret);
  lx::sdk1::ControlFrame again;
  if (lx::sdk1::parse(lx::sdk1::encode(f), again) != lx::sdk1::ParseError::kNone) __builtin_trap();
  if (again.type != f.type || again.seq != f.seq || again.cmd_set != f.cmd_set ||
      again.cmd_id != f.cmd_id || again.payload != f.payload) {
    __builtin_trap();
  }
}

void fuzz_sdk2(std::span<const std::byte> data) {
  lx::sdk2::ControlFrame f;
  if (lx::sdk2::parse(data, f) != lx::sdk2::ParseError::kNone) return;
  lx::sdk2::DiscoveryAck disc;
  (void)lx::sdk2::parse_discovery_ack(f, disc);
  lx::sdk2::SetParamsAck ack;
  (void)lx::sdk2::parse_set_params_ack(f, ack);
  lx::sdk2::ControlFrame again;
  if (lx::sdk2::parse(lx::sdk2::encode(f), again) != lx::sdk2::ParseError::kNone) __builtin_trap();
  if (again.seq != f.seq || again.cmd_id != f.cmd_id || again.cmd_type != f.cmd_type ||
      again.sender_type != f.sender_type || again.data != f.data) {
    __builtin_trap();
  }
}

void fuzz_device(lx::Protocol protocol, std::span<const std::byte> data) {
  lx::DeviceConfig config;
  config.protocol = protocol;
  config.host_ip = 0xC0A80132;
  lx::LivoxDevice device(config);
  std::vector<lx::OutgoingFrame> out;
  livod::HostTime now(1'000'000'000);
  lx::DeviceCounters before = device.counters();
  std::size_t at = 0;
  while (at + 3 <= data.size()) {
    const std::size_t length =
        std::to_integer<std::size_t>(data[at]) | (std::to_integer<std::size_t>(data[at + 1]) << 8);
    now += livod::Nanoseconds(std::to_integer<std::int64_t>(data[at + 2]) * 10'000'000);
    at += 3;
    const std::size_t take = length < data.size() - at ? length : data.size() - at;
    const auto datagram = data.subspan(at, take);
    at += take;
    // The low bit of the length picks where it came from: the LiDAR, or data activity.
    if ((length & 1U) != 0) device.on_data(now);
    device.on_control_datagram(datagram, 0xC0A8010A, now);
    out.clear();
    device.tick(now, out);
    for (const lx::OutgoingFrame& f : out) {
      if (protocol == lx::Protocol::kSdk1) {
        lx::sdk1::ControlFrame parsed;
        if (lx::sdk1::parse(f.bytes, parsed) != lx::sdk1::ParseError::kNone) __builtin_trap();
      } else {
        lx::sdk2::ControlFrame parsed;
        if (lx::sdk2::parse(f.bytes, parsed) != lx::sdk2::ParseError::kNone) __builtin_trap();
      }
    }
    const lx::DeviceCounters& c = device.counters();
    if (c.frames_sent < before.frames_sent || c.acks < before.acks ||
        c.bad_frames < before.bad_frames || c.stale_events < before.stale_events ||
        c.reconnects < before.reconnects || c.reconnects > c.stale_events) {
      __builtin_trap();
    }
    before = c;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  if (size < 1) return 0;
  const std::span<const std::byte> all(reinterpret_cast<const std::byte*>(bytes), size);
  const auto data = all.subspan(1);
  switch (std::to_integer<unsigned>(all[0]) % 4) {
    case 0:
      fuzz_sdk1(data);
      break;
    case 1:
      fuzz_sdk2(data);
      break;
    case 2:
      fuzz_device(lx::Protocol::kSdk1, data);
      break;
    default:
      fuzz_device(lx::Protocol::kSdk2, data);
      break;
  }
  return 0;
}
