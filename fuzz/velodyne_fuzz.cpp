// libFuzzer target for the Velodyne decoders: data packets (every model, both azimuth modes),
// position packets, $GPRMC sentences, VeloView XML calibrations, and the stateful decoder fed a
// stream cut from the input. Crashes, sanitizer reports and exceptions other than livod::Error
// are findings.
//
// Input layout: byte 0 selects what to fuzz, the rest is the payload. Payloads for the fixed-size
// packets are zero-padded or truncated to 1206 / 512 bytes so that the fuzzer explores their
// contents rather than their lengths (wrong lengths are covered by the stream mode).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "drivers/velodyne/data_packet.hpp"
#include "drivers/velodyne/nmea.hpp"
#include "drivers/velodyne/position_packet.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"

namespace {

using livod::drivers::velodyne::Model;

std::vector<std::byte> sized(std::span<const std::byte> data, std::size_t size) {
  std::vector<std::byte> out(size, std::byte{0});
  for (std::size_t i = 0; i < size && i < data.size(); ++i) out[i] = data[i];
  return out;
}

void fuzz_data_packet(Model model, bool veloview, std::span<const std::byte> data) {
  namespace v = livod::drivers::velodyne;
  v::DecodeSettings settings;
  if (veloview && (model == Model::kVlp16 || model == Model::kHdl32e)) {
    settings.azimuth = v::AzimuthInterpolation::kVeloView;
  }
  const v::DataPacketDecoder decoder(model, v::default_calibration(model), settings);
  std::vector<v::DecodedReturn> out(v::DataPacketDecoder::kMaxReturns);
  const auto packet = sized(data, livod::drivers::velodyne::wire::kDataPacketSize);
  const double fallback_rate = data.empty() ? 0.0 : static_cast<double>(data[0]) * 1e-6;
  const double dating_rate = data.size() < 2 ? 0.0 : static_cast<double>(data[1]) * 1e-5;
  const auto r = decoder.decode(packet, fallback_rate, out, dating_rate);
  if (r.count > out.size()) __builtin_trap();
  for (std::size_t i = 0; i < r.count; ++i) {
    // Every emitted point comes from a non-zero range and has finite coordinates.
    if (!(out[i].distance_m > 0.0f) || out[i].x != out[i].x || out[i].y != out[i].y)
      __builtin_trap();
    // Firing times never go back from the block's table time (a FOV delay only adds).
    if (out[i].t_offset_ns < decoder.timing().offset_ns(r.dual, out[i].block, 0)) __builtin_trap();
  }
}

void fuzz_stream(Model model, std::span<const std::byte> data) {
  namespace v = livod::drivers::velodyne;
  v::VelodyneOptions options;
  options.model = model;
  options.cut = static_cast<v::ScanCut>(data.empty() ? 0 : static_cast<int>(data[0]) % 3);
  options.cut_angle_deg = 90.0;
  options.cut_period_ns = 50'000'000;
  // A configured FOV window (270 -> 90 degrees) on some inputs: the skipped-sector accounting.
  if (!data.empty() && (static_cast<int>(data[0]) & 0x08) != 0) {
    options.fov = livod::drivers::AzimuthWindow{270.0, 90.0};
  }
  v::VelodyneDecoder decoder(options);
  livod::drivers::DecoderSinks sinks;
  std::uint64_t points = 0;
  sinks.on_scan = [&points](const livod::LidarScan& scan) { points += scan.size(); };
  sinks.on_imu = [](const livod::ImuSample&) {};
  // Chunks: a 2-byte length prefix each (mostly 1206 or 512), the stream's own bytes as payload.
  std::size_t at = 1;
  std::int64_t host_ns = 1'000'000'000;
  while (at + 2 <= data.size()) {
    const auto selector = static_cast<std::uint8_t>(data[at]);
    std::size_t length = static_cast<std::size_t>(data[at + 1]) * 8;
    if (selector % 4 == 0) length = 1206;
    if (selector % 4 == 1) length = 512;
    at += 2;
    const auto payload = sized(data.subspan(at), length);
    at += std::min(length, data.size() - at);
    host_ns += 500'000;
    decoder.on_packet(livod::drivers::PacketView{payload, host_ns, 2368}, sinks);
  }
  decoder.flush(sinks);
  if (decoder.counters().points != points) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::byte> data(reinterpret_cast<const std::byte*>(bytes + 1), size - 1);
  const std::uint8_t mode = bytes[0];
  const auto model = static_cast<Model>((mode >> 3) % 5);
  try {
    switch (mode % 8) {
      case 0:
      case 1:
        fuzz_data_packet(model, mode % 8 == 1, data);
        break;
      case 2: {
        const auto packet = sized(data, livod::drivers::velodyne::wire::kPositionPacketSize);
        const auto r = livod::drivers::velodyne::decode_position_packet(packet);
        if (r.status == livod::drivers::velodyne::PositionDecodeStatus::kOk) {
          (void)livod::drivers::velodyne::hdl32e_imu_in_lidar_frame(r.packet);
        }
        break;
      }
      case 3:
        (void)livod::drivers::velodyne::parse_rmc(
            std::string_view(reinterpret_cast<const char*>(data.data()), data.size()));
        break;
      case 4:
        (void)livod::drivers::velodyne::parse_veloview_xml(
            std::string_view(reinterpret_cast<const char*>(data.data()), data.size()), "fuzz");
        break;
      default:
        fuzz_stream(model, data);
        break;
    }
  } catch (const livod::Error&) {
    // Rejected input: the expected outcome for malformed calibrations.
  }
  return 0;
}
