#include "drivers/velodyne/velodyne_family.hpp"

#include <cmath>

#include "core/error.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr UdpPorts kPorts{.lidar = 2368, .position = 8308};  // VROS velodyne_driver input.h
constexpr std::array<std::string_view, 2> kVlp16Aliases{"PUCK", "PUCK-LITE"};
constexpr std::array<std::string_view, 1> kVlp32cAliases{"ULTRA-PUCK"};
constexpr std::array<std::string_view, 1> kVls128Aliases{"ALPHA-PRIME"};
constexpr double kReturnsPerPacket = 12 * 32;

// Points per second: the single-return packet rates of model.cpp (VROS driver.cc) x 384 returns
// per packet. Ranges and range accuracy (typical): Velodyne datasheets (VLP-16 / Puck Hi-Res
// 100 m, +-3 cm; VLP-32C 200 m, +-3 cm; HDL-32E 100 m, +-2 cm; VLS-128 245 m, +-3 cm). Beam
// divergence: not in livod's sources.
constexpr std::array<LidarModelInfo, 5> kModels{{
    {"VLP-16", kVlp16Aliases, "Velodyne VLP-16 (Puck)", 16, 754.0 * kReturnsPerPacket, 10.0, 0.0,
     100.0, 0.03, std::nullopt, false, kPorts},
    {"PUCK-HI-RES",
     {},
     "Velodyne Puck Hi-Res",
     16,
     754.0 * kReturnsPerPacket,
     10.0,
     0.0,
     100.0,
     0.03,
     std::nullopt,
     false,
     kPorts},
    {"VLP-32C", kVlp32cAliases, "Velodyne VLP-32C (Ultra Puck)", 32, 1507.0 * kReturnsPerPacket,
     10.0, 0.0, 200.0, 0.03, std::nullopt, false, kPorts},
    {"HDL-32E",
     {},
     "Velodyne HDL-32E (its IMU in the position packets)",
     32,
     1808.0 * kReturnsPerPacket,
     10.0,
     0.0,
     100.0,
     0.02,
     std::nullopt,
     true,
     kPorts},
    {"VLS-128", kVls128Aliases, "Velodyne VLS-128 (Alpha Prime)", 128, 6253.9 * kReturnsPerPacket,
     10.0, 0.0, 245.0, 0.03, std::nullopt, false, kPorts},
}};
constexpr std::array<std::string_view, 2> kPortNames{"lidar", "position"};
constexpr std::array<CutMode, 2> kCuts{CutMode::kAzimuth, CutMode::kTime};

void read_settings(SettingsReader& reader, LidarSettings& out) {
  VelodyneSettings s;
  if (const auto fov = reader.degree_pair("fov_deg")) s.fov = AzimuthWindow{(*fov)[0], (*fov)[1]};
  out = s;
}

std::unique_ptr<LidarDecoder> make(const LidarDecoderConfig& config) {
  const LidarModelInfo* info = velodyne_family().find_model(config.model);
  const auto model = info ? model_from_name(info->name) : std::nullopt;
  if (!model) {
    throw Error("unknown Velodyne model '" + config.model +
                "'; known: " + velodyne_family().model_list());
  }
  if (config.metadata) {
    throw Error("the " + std::string(info->name) +
                " takes a calibration file (VeloView XML or ROS/nebula YAML), not metadata");
  }
  VelodyneOptions options;
  options.model = *model;
  options.calibration_file = config.calibration;
  if (const auto* s = std::get_if<VelodyneSettings>(&config.settings)) options.fov = s->fov;
  if (config.cut) {
    switch (config.cut->mode) {
      case CutMode::kAzimuth:
        options.cut =
            config.cut->azimuth_deg == 0.0 ? ScanCut::kAzimuthDecrease : ScanCut::kAzimuthAngle;
        options.cut_angle_deg = config.cut->azimuth_deg;
        break;
      case CutMode::kTime:
        options.cut = ScanCut::kTimePeriod;
        options.cut_period_ns = std::llround(config.cut->period_s * 1e9);
        break;
      case CutMode::kFrameId:
        throw Error("Velodyne packets carry no frame id (frame_cut azimuth or time)");
    }
  }
  return std::make_unique<VelodyneDecoder>(options);
}

}  // namespace

const LidarFamily& velodyne_family() {
  static const LidarFamily kFamily{
      .driver = "velodyne",
      .vendor = "Velodyne",
      .models = kModels,
      .model_required = true,
      .port_names = kPortNames,
      .cut_modes = kCuts,
      .file = DecoderFile::kCalibrationOptional,
      .lidar_datagram_bytes = wire::kDataPacketSize,
      .aux_datagram_bytes = wire::kPositionPacketSize,  // position packets (port 8308)
      .sensor_time_wrap_ns = 3'600'000'000'000LL,       // microseconds past the top of the hour
      .read_settings = &read_settings,
      .make_decoder = &make,
  };
  return kFamily;
}

}  // namespace livod::drivers::velodyne
