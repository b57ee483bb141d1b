// libFuzzer target: Livox point/IMU packet decoding (SDK1 and SDK2) and LivoxDecoder scan
// assembly on arbitrary bytes.
//
// Input: byte 0 selects the mode, byte 1 the model / decoder parameters, the rest is the data.
//   mode 0: decode_sdk1 on one payload        mode 1: decode_sdk2 on one payload
//   mode 2: a LivoxDecoder fed a stream of payloads, each prefixed by a 2-byte little-endian length
//           (a truncated last chunk is fed as it is), with the receive time advancing by a
//           fuzzed amount; flushed at the end.
// Findings: crashes and sanitizer reports, and broken output invariants (point count beyond the
// packet capacity, non-finite coordinates of a valid point, a scan whose arrays disagree in length
// or whose point offsets are negative) which abort via __builtin_trap.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include "drivers/lidar_decoder.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "drivers/livox/packets.hpp"

namespace {

namespace lx = livod::livox;

constexpr std::array<const char*, 7> kModels{"AVIA",   "HORIZON", "TELE-15", "MID-40",
                                             "MID-70", "MID-360", "HAP"};

void check_packet(lx::DecodeError e, const lx::LivoxPacket& p) {
  if (e != lx::DecodeError::kNone) return;
  if (p.count > lx::kMaxPointsPerPacket) __builtin_trap();
  for (std::size_t i = 0; i < p.count; ++i) {
    const lx::LivoxPoint& q = p.points[i];
    if (q.valid && !(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z))) {
      __builtin_trap();
    }
  }
}

void check_scan(const livod::LidarScan& s) {
  const std::size_t n = s.x.size();
  if (s.y.size() != n || s.z.size() != n || s.intensity.size() != n || s.ring.size() != n ||
      s.return_index.size() != n || s.t_offset_ns.size() != n || s.valid.size() != n) {
    __builtin_trap();
  }
  for (const std::int32_t t : s.t_offset_ns) {
    if (t < 0) __builtin_trap();
  }
}

void fuzz_stream(const lx::LivoxModel& model, std::span<const std::byte> data) {
  lx::LivoxDecoderOptions options;
  options.scan_period_ns = 50'000'000;
  lx::LivoxDecoder decoder(model, options);
  livod::drivers::DecoderSinks sinks;
  sinks.on_scan = [](const livod::LidarScan& s) { check_scan(s); };
  sinks.on_imu = [](const livod::ImuSample&) {};
  std::int64_t rx_ns = 1'000'000'000;
  std::size_t at = 0;
  std::uint64_t fed = 0;
  while (at + 2 <= data.size()) {
    const std::size_t length =
        std::to_integer<std::size_t>(data[at]) | (std::to_integer<std::size_t>(data[at + 1]) << 8);
    at += 2;
    const std::size_t take = length < data.size() - at ? length : data.size() - at;
    decoder.on_packet(livod::drivers::PacketView{data.subspan(at, take), rx_ns, model.data_port},
                      sinks);
    ++fed;
    at += take;
    rx_ns += static_cast<std::int64_t>(length) * 1000;
  }
  decoder.flush(sinks);
  const auto& c = decoder.counters();
  if (c.packets != fed) __builtin_trap();
  if (c.lidar_packets + c.imu_packets + c.decode_errors > c.packets) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  if (size < 2) return 0;
  const std::span<const std::byte> all(reinterpret_cast<const std::byte*>(bytes), size);
  const auto mode = std::to_integer<unsigned>(all[0]) % 3;
  const auto selector = std::to_integer<unsigned>(all[1]);
  const auto data = all.subspan(2);
  static lx::LivoxPacket packet;  // large (100 points): not on the stack per input
  switch (mode) {
    case 0: {
      const std::uint32_t interval = (selector & 1U) != 0 ? 10000 : 4167;
      const std::uint8_t lines = (selector & 2U) != 0 ? 1 : 6;
      check_packet(lx::decode_sdk1(data, interval, lines, packet), packet);
      break;
    }
    case 1:
      check_packet(lx::decode_sdk2(data, (selector & 1U) != 0 ? 6 : 4, packet), packet);
      break;
    default:
      fuzz_stream(*lx::livox_model(kModels[selector % kModels.size()]), data);
      break;
  }
  return 0;
}
