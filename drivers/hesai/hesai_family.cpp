#include "drivers/hesai/hesai_family.hpp"

#include <cmath>

#include "core/error.hpp"
#include "drivers/hesai/hesai_decoder.hpp"
#include "drivers/hesai/packet.hpp"

namespace livod::drivers::hesai {
namespace {

constexpr UdpPorts kPorts{.lidar = kDataPort, .position = kGpsPort};
// Spellings differing only in case, "-", "_" or spaces need no alias (normalise_model_name).
constexpr std::array<std::string_view, 1> kXt32Aliases{"XT32"};

// Points per second: channels x firing rounds per second (model.hpp). Ranges and range accuracy:
// Hesai datasheets (PandarXT-32: 0.05-120 m, +-1 cm; Pandar40P: 0.3-200 m, +-2 cm). Beam
// divergence: not in livod's sources. Neither model has an IMU.
constexpr std::array<LidarModelInfo, 2> kFamilyModels{{
    {"PANDARXT32", kXt32Aliases, "Hesai PandarXT-32 (needs its angle correction file)", 32,
     640'000.0, 10.0, 0.05, 120.0, 0.01, std::nullopt, false, kPorts},
    {"PANDAR40P",
     {},
     "Hesai Pandar40P (needs its angle correction file)",
     40,
     720'000.0,
     10.0,
     0.3,
     200.0,
     0.02,
     std::nullopt,
     false,
     kPorts},
}};
constexpr std::array<std::string_view, 2> kPortNames{"lidar", "position"};
constexpr std::array<CutMode, 2> kCuts{CutMode::kAzimuth, CutMode::kTime};

void read_settings(SettingsReader& reader, LidarSettings& out) {
  HesaiSettings s;
  if (const auto fov = reader.degree_pair("fov_deg")) s.fov = AzimuthWindow{(*fov)[0], (*fov)[1]};
  if (const auto v = reader.number("min_range_m", 0.0, 1000.0)) s.min_range_m = *v;
  if (const auto v = reader.number("max_range_m", 0.0, 1000.0)) s.max_range_m = *v;
  if (s.min_range_m && s.max_range_m && *s.min_range_m >= *s.max_range_m) {
    reader.error("max_range_m", "must be larger than min_range_m");
  }
  out = s;
}

std::unique_ptr<LidarDecoder> make(const LidarDecoderConfig& config) {
  const LidarModelInfo* info = hesai_family().find_model(config.model);
  const auto model = info ? model_from_name(info->name) : std::nullopt;
  if (!model) {
    throw Error("unknown Hesai model '" + config.model +
                "'; known: " + hesai_family().model_list());
  }
  if (config.metadata) {
    throw Error("the " + std::string(info->name) +
                " takes its angle correction file (calibration), not metadata");
  }
  HesaiOptions options;
  options.model = *model;
  options.calibration_file = config.calibration;
  options.min_range_m = info->min_range_m;
  options.max_range_m = info->max_range_m;
  if (const auto* s = std::get_if<HesaiSettings>(&config.settings)) {
    options.fov = s->fov;
    if (s->min_range_m) options.min_range_m = *s->min_range_m;
    if (s->max_range_m) options.max_range_m = *s->max_range_m;
  }
  if (config.cut) {
    switch (config.cut->mode) {
      case CutMode::kAzimuth:
        options.cut = ScanCut::kAzimuth;
        options.cut_angle_deg = config.cut->azimuth_deg;
        break;
      case CutMode::kTime:
        options.cut = ScanCut::kTimePeriod;
        options.cut_period_ns = std::llround(config.cut->period_s * 1e9);
        break;
      case CutMode::kFrameId:
        throw Error("Hesai packets carry no frame id (frame_cut azimuth or time)");
    }
  }
  return std::make_unique<HesaiDecoder>(options);
}

}  // namespace

const LidarFamily& hesai_family() {
  static const LidarFamily kFamily{
      .driver = "hesai",
      .vendor = "Hesai",
      .models = kFamilyModels,
      .model_required = true,
      .port_names = kPortNames,
      .cut_modes = kCuts,
      .file = DecoderFile::kCalibrationRequired,
      .lidar_datagram_bytes = kPandar40pPacketSizeWithSequence,
      .aux_datagram_bytes = kGpsPacketSize,
      .sensor_time_wrap_ns = 0,
      .read_settings = &read_settings,
      .make_decoder = &make,
  };
  return kFamily;
}

}  // namespace livod::drivers::hesai
