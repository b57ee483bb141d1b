#include "drivers/livox/livox_family.hpp"

#include <cmath>

#include "core/error.hpp"
#include "drivers/livox/livox_decoder.hpp"

namespace livod::livox {
namespace {

using drivers::CutMode;
using drivers::LidarModelInfo;
using drivers::UdpPorts;

// Host ports livod asks for / the vendor defaults: SDK1's first device has data and IMU on 56001
// (command 55501); Mid-360 56301/56401 (command 56101, push 56201); HAP 57000/58000 (command
// 56000). sensor-protocols.md 1.1, 2.1.
// The largest datagrams: SDK1 dual-return Cartesian points (18 + 96 x 14 = 1362 bytes), SDK2 the
// HAP's / Mid-360's 96-point packets (36 + 96 x 14 = 1380 bytes).
constexpr std::size_t kSdk1MaxDatagramBytes = 1362;
constexpr std::size_t kSdk2MaxDatagramBytes = 1380;
constexpr UdpPorts kSdk1Ports{.lidar = 56001, .imu = 56001, .command = 55501};
constexpr UdpPorts kMid360Ports{.lidar = 56301, .imu = 56401, .command = 56101, .push = 56201};
constexpr UdpPorts kHapPorts{.lidar = 57000, .imu = 58000, .command = 56000};

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Point rates, ranges (at 80 % reflectivity), range random error (1 sigma, 2 cm at 20 m) and
// beam divergence (vertical, the larger axis): Livox user manuals / datasheets (HAP: its manual,
// Table 1.2.1). Mid-360's divergence is not in livod's sources. Beams = the scan lines (the
// decoder's `line` = point index mod lines).
constexpr std::array<LidarModelInfo, 5> kSdk1Models{{
    {"AVIA",
     {},
     "Livox Avia (SDK1), 70.4 x 77.2 deg non-repetitive",
     6,
     240'000.0,
     10.0,
     0.0,
     450.0,
     0.02,
     0.28 * kDeg,
     true,
     kSdk1Ports},
    {"HORIZON",
     {},
     "Livox Horizon (SDK1)",
     6,
     240'000.0,
     10.0,
     0.0,
     260.0,
     0.02,
     0.28 * kDeg,
     true,
     kSdk1Ports},
    {"TELE-15",
     {},
     "Livox Tele-15 (SDK1)",
     6,
     240'000.0,
     10.0,
     0.0,
     500.0,
     0.02,
     0.12 * kDeg,
     true,
     kSdk1Ports},
    {"MID-40",
     {},
     "Livox Mid-40 (SDK1, no IMU)",
     1,
     100'000.0,
     10.0,
     0.0,
     260.0,
     0.02,
     0.28 * kDeg,
     false,
     kSdk1Ports},
    {"MID-70",
     {},
     "Livox Mid-70 (SDK1, no IMU)",
     1,
     100'000.0,
     10.0,
     0.0,
     260.0,
     0.02,
     0.28 * kDeg,
     false,
     kSdk1Ports},
}};
constexpr std::array<LidarModelInfo, 2> kSdk2Models{{
    {"MID-360",
     {},
     "Livox Mid-360 (SDK2)",
     4,
     200'000.0,
     10.0,
     0.1,
     70.0,
     0.02,
     std::nullopt,
     true,
     kMid360Ports},
    {"HAP",
     {},
     "Livox HAP (SDK2)",
     6,
     452'000.0,
     10.0,
     0.5,
     150.0,
     0.02,
     0.28 * kDeg,
     true,
     kHapPorts},
}};

// What the decoder needs beyond the table: SDK1 point intervals (sensor-protocols.md 1.3).
struct Timing {
  std::string_view name;
  Protocol protocol;
  std::uint32_t point_interval_ns;
};
constexpr std::array<Timing, 7> kTiming{{
    {"AVIA", Protocol::kSdk1, 4167},
    {"HORIZON", Protocol::kSdk1, 4167},
    {"TELE-15", Protocol::kSdk1, 4167},
    {"MID-40", Protocol::kSdk1, 10000},
    {"MID-70", Protocol::kSdk1, 10000},
    {"MID-360", Protocol::kSdk2, 0},
    {"HAP", Protocol::kSdk2, 0},
}};

constexpr std::array<std::string_view, 3> kSdk1PortNames{"lidar", "imu", "command"};
constexpr std::array<std::string_view, 4> kSdk2PortNames{"lidar", "imu", "command", "push"};
// Non-repetitive scan patterns have no azimuth wrap and no frame counter: scans are time windows.
constexpr std::array<CutMode, 1> kCuts{CutMode::kTime};

const LidarModelInfo* find_info(std::string_view name) {
  if (const auto* m = livox_sdk1_family().find_model(name)) return m;
  return livox_sdk2_family().find_model(name);
}

}  // namespace

std::optional<LivoxModel> livox_model(const std::string& name) {
  const LidarModelInfo* info = find_info(name);
  if (info == nullptr) return std::nullopt;
  for (const Timing& t : kTiming) {
    if (t.name == info->name) {
      return LivoxModel{std::string(info->name), t.protocol,
                        t.point_interval_ns,     static_cast<std::uint8_t>(info->beams),
                        info->ports.lidar,       info->ports.imu};
    }
  }
  return std::nullopt;
}

std::unique_ptr<drivers::LidarDecoder> make_livox_decoder(
    const drivers::LidarDecoderConfig& config) {
  const auto model = livox_model(config.model);
  if (!model) throw Error("unknown Livox model '" + config.model + "'");
  if (config.metadata || config.calibration) {
    throw Error("Livox " + model->name +
                " needs no metadata or calibration file (its packets carry Cartesian points)");
  }
  LivoxDecoderOptions options;
  if (config.cut) {
    if (config.cut->mode != CutMode::kTime) {
      throw Error("Livox scans are cut by time only (frame_cut: {mode: time})");
    }
    options.scan_period_ns = std::llround(config.cut->period_s * 1e9);
  }
  return std::make_unique<LivoxDecoder>(*model, options);
}

const drivers::LidarFamily& livox_sdk1_family() {
  static const drivers::LidarFamily kFamily{
      .driver = "livox_sdk1",
      .vendor = "Livox",
      .models = kSdk1Models,
      .model_required = true,
      .port_names = kSdk1PortNames,
      .cut_modes = kCuts,
      .file = drivers::DecoderFile::kNone,
      .lidar_datagram_bytes = kSdk1MaxDatagramBytes,
      .aux_datagram_bytes = kSdk1MaxDatagramBytes,
      .sensor_time_wrap_ns = 0,
      .read_settings = nullptr,
      .make_decoder = &make_livox_decoder,
  };
  return kFamily;
}

const drivers::LidarFamily& livox_sdk2_family() {
  static const drivers::LidarFamily kFamily{
      .driver = "livox_sdk2",
      .vendor = "Livox",
      .models = kSdk2Models,
      .model_required = true,
      .port_names = kSdk2PortNames,
      .cut_modes = kCuts,
      .file = drivers::DecoderFile::kNone,
      .lidar_datagram_bytes = kSdk2MaxDatagramBytes,
      .aux_datagram_bytes = kSdk2MaxDatagramBytes,
      .sensor_time_wrap_ns = 0,
      .read_settings = nullptr,
      .make_decoder = &make_livox_decoder,
  };
  return kFamily;
}

}  // namespace livod::livox
