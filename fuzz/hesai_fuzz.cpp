// libFuzzer target for the Hesai decoders: point cloud packets of each model, angle correction
// files, and the stateful HesaiDecoder (both cut modes, with and without a start/end angle window)
// fed a stream cut from the input. Crashes, sanitizer reports, exceptions other than livod::Error
// and broken output invariants (counts, non-finite points, negative or inconsistent point
// offsets) are findings.
//
// Input layout: byte 0 selects the mode and the model, the rest is the payload.
//   mode 0: decode_packet on one payload, sized to the model's packet length (contents explored)
//   mode 1: decode_packet on the raw payload (lengths explored)
//   mode 2: parse_angle_corrections on the payload as text
//   mode 3: a HesaiDecoder fed payloads, each prefixed by a selector byte (0: the model's packet
//           length, 1: 512 bytes (GPS), else the next byte x 8) and a receive-time step byte.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "drivers/hesai/calibration.hpp"
#include "drivers/hesai/hesai_decoder.hpp"
#include "drivers/hesai/packet.hpp"

namespace {

namespace hs = livod::drivers::hesai;

std::vector<std::byte> sized(std::span<const std::byte> data, std::size_t size) {
  std::vector<std::byte> out(size, std::byte{0});
  for (std::size_t i = 0; i < size && i < data.size(); ++i) out[i] = data[i];
  return out;
}

std::size_t packet_size(hs::Model model, bool variant) {
  if (model == hs::Model::kPandarXT32) {
    return variant ? hs::kXt32PacketSizeNoSequence : hs::kXt32PacketSize;
  }
  return variant ? hs::kPandar40pPacketSizeWithSequence : hs::kPandar40pPacketSize;
}

void check_packet(hs::PacketError e, const hs::HesaiPacket& p) {
  if (e != hs::PacketError::kNone) return;
  if (p.returns < 1 || p.returns > 2) __builtin_trap();
  for (int b = 0; b < hs::traits(p.model).blocks; ++b) {
    if (p.azimuth[static_cast<std::size_t>(b)] >= 36000) __builtin_trap();
  }
  if (!(p.distance_unit_m > 0.0)) __builtin_trap();
  // A decoded packet encodes back to a packet that decodes to the same fields.
  hs::HesaiPacket again;
  if (hs::decode_packet(p.model, hs::encode_packet(p), again) != hs::PacketError::kNone) {
    __builtin_trap();
  }
  if (again.timestamp_ns != p.timestamp_ns || again.udp_sequence != p.udp_sequence ||
      again.returns != p.returns || again.return_mode != p.return_mode) {
    __builtin_trap();
  }
  // Only the model's blocks and channels are the packet's (the rest of the fixed-capacity
  // arrays keeps whatever an earlier, larger packet left).
  const hs::ModelTraits& t = hs::traits(p.model);
  for (int b = 0; b < t.blocks; ++b) {
    if (again.azimuth[static_cast<std::size_t>(b)] != p.azimuth[static_cast<std::size_t>(b)]) {
      __builtin_trap();
    }
    for (int c = 0; c < t.channels; ++c) {
      if (again.raw_distance(b, c) != p.raw_distance(b, c) ||
          again.raw_reflectivity(b, c) != p.raw_reflectivity(b, c)) {
        __builtin_trap();
      }
    }
  }
}

void check_scan(const livod::LidarScan& s) {
  const std::size_t n = s.x.size();
  if (s.y.size() != n || s.z.size() != n || s.intensity.size() != n || s.ring.size() != n ||
      s.return_index.size() != n || s.t_offset_ns.size() != n || s.valid.size() != n) {
    __builtin_trap();
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (s.t_offset_ns[i] < 0) __builtin_trap();
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || !std::isfinite(s.z[i])) {
      __builtin_trap();
    }
  }
}

hs::AngleCorrections corrections(hs::Model model) {
  hs::AngleCorrections k;
  k.source = "fuzz";
  const int n = hs::traits(model).channels;
  for (int c = 0; c < n; ++c) k.channels.push_back({15.0 - c, (c % 3 - 1) * 0.5});
  return k;
}

void fuzz_stream(hs::Model model, std::uint8_t flags, std::span<const std::byte> data) {
  hs::HesaiOptions options;
  options.model = model;
  options.cut = (flags & 1U) != 0 ? hs::ScanCut::kTimePeriod : hs::ScanCut::kAzimuth;
  options.cut_angle_deg = (flags & 2U) != 0 ? 270.5 : 0.0;
  options.cut_period_ns = 50'000'000;
  options.min_range_m = 0.05;
  if ((flags & 4U) != 0) options.fov = livod::drivers::AzimuthWindow{300.0, 60.0};
  hs::HesaiDecoder decoder(options, corrections(model));
  livod::drivers::DecoderSinks sinks;
  std::uint64_t points = 0;
  sinks.on_scan = [&points](const livod::LidarScan& s) {
    check_scan(s);
    points += s.size();
  };
  std::int64_t host_ns = 1'000'000'000;
  std::size_t at = 0;
  std::uint64_t fed = 0;
  while (at + 2 <= data.size()) {
    const auto selector = std::to_integer<unsigned>(data[at]);
    const auto step = std::to_integer<unsigned>(data[at + 1]);
    at += 2;
    std::size_t length = packet_size(model, (selector & 0x80U) != 0);
    if (selector % 4 == 1) length = hs::kGpsPacketSize;
    if (selector % 4 >= 2) length = (selector & 0x7FU) * 8;
    const auto payload = sized(data.subspan(at), length);
    at += std::min(length, data.size() - at);
    host_ns += static_cast<std::int64_t>(step) * 10'000;
    decoder.on_packet(livod::drivers::PacketView{payload, host_ns, hs::kDataPort}, sinks);
    ++fed;
  }
  decoder.flush(sinks);
  const auto& c = decoder.counters();
  if (c.packets != fed || c.points != points) __builtin_trap();
  if (c.lidar_packets + c.aux_packets + c.decode_errors != c.packets) __builtin_trap();
  if (c.incomplete_scans > c.scans) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::byte> data(reinterpret_cast<const std::byte*>(bytes + 1), size - 1);
  const std::uint8_t selector = bytes[0];
  const auto model = (selector & 0x10U) != 0 ? hs::Model::kPandar40P : hs::Model::kPandarXT32;
  static hs::HesaiPacket packet;  // large: not on the stack per input
  try {
    switch (selector % 4) {
      case 0:
        check_packet(hs::decode_packet(
                         model, sized(data, packet_size(model, (selector & 0x20U) != 0)), packet),
                     packet);
        break;
      case 1:
        check_packet(hs::decode_packet(model, data, packet), packet);
        break;
      case 2:
        (void)hs::parse_angle_corrections(
            std::string_view(reinterpret_cast<const char*>(data.data()), data.size()), "fuzz");
        break;
      default:
        fuzz_stream(model, static_cast<std::uint8_t>(selector >> 5), data);
        break;
    }
  } catch (const livod::Error&) {
    // Rejected input: the expected outcome for malformed correction files.
  }
  return 0;
}
