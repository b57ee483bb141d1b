#include "daemon/config/sensor_models.hpp"

#include <algorithm>

namespace livod::daemon {

namespace {

FrameCutMode from_cut_mode(drivers::CutMode mode) {
  switch (mode) {
    case drivers::CutMode::kAzimuth:
      return FrameCutMode::azimuth;
    case drivers::CutMode::kTime:
      return FrameCutMode::time;
    case drivers::CutMode::kFrameId:
      return FrameCutMode::frame_id;
  }
  return FrameCutMode::time;
}

}  // namespace

const drivers::LidarFamily* lidar_family(Driver driver) {
  return drivers::find_family(enum_name(driver));
}

std::vector<std::string> known_models(Driver driver) {
  std::vector<std::string> models;
  if (const auto* family = lidar_family(driver)) {
    for (const auto& m : family->models) models.emplace_back(m.name);
  }
  return models;
}

bool model_required(Driver driver) {
  const auto* family = lidar_family(driver);
  return family != nullptr && family->model_required;
}

std::optional<std::string> canonical_model(Driver driver, std::string_view model) {
  const auto* family = lidar_family(driver);
  if (family == nullptr) return std::string(model);
  if (const auto* m = family->find_model(model)) return std::string(m->name);
  return std::nullopt;
}

bool driver_has_internal_imu_models(Driver driver) {
  const auto* family = lidar_family(driver);
  if (family == nullptr) return false;
  return std::any_of(family->models.begin(), family->models.end(),
                     [](const drivers::LidarModelInfo& m) { return m.internal_imu; });
}

bool model_has_internal_imu(Driver driver, std::string_view canonical) {
  const auto* family = lidar_family(driver);
  if (family == nullptr) return false;
  const auto* m = family->find_model(canonical);
  // A sensor that names no model (Ouster: the metadata tells) has one if every model has.
  if (m == nullptr) {
    return std::all_of(family->models.begin(), family->models.end(),
                       [](const drivers::LidarModelInfo& x) { return x.internal_imu; });
  }
  return m->internal_imu;
}

UdpPorts default_ports(Driver driver, std::string_view canonical) {
  const auto* family = lidar_family(driver);
  if (family == nullptr) return {};
  const auto* m = family->find_model(canonical);
  return m != nullptr ? m->ports : family->models.front().ports;
}

std::vector<std::string> port_names(Driver driver) {
  std::vector<std::string> names;
  if (const auto* family = lidar_family(driver)) {
    for (const auto n : family->port_names) names.emplace_back(n);
  }
  return names;
}

FrameCutMode default_frame_cut(Driver driver) {
  const auto* family = lidar_family(driver);
  return family != nullptr ? from_cut_mode(family->default_cut()) : FrameCutMode::time;
}

std::vector<FrameCutMode> allowed_frame_cuts(Driver driver) {
  std::vector<FrameCutMode> modes;
  if (const auto* family = lidar_family(driver)) {
    for (const auto m : family->cut_modes) modes.push_back(from_cut_mode(m));
  }
  return modes;
}

drivers::CutMode to_cut_mode(FrameCutMode mode) {
  switch (mode) {
    case FrameCutMode::azimuth:
      return drivers::CutMode::kAzimuth;
    case FrameCutMode::time:
      return drivers::CutMode::kTime;
    case FrameCutMode::frame_id:
      return drivers::CutMode::kFrameId;
  }
  return drivers::CutMode::kTime;
}

drivers::LidarDecoderConfig decoder_config(const SensorConfig& sensor) {
  drivers::LidarDecoderConfig config;
  const auto* family = lidar_family(sensor.driver);
  // A sensor that names no model (an Ouster: its metadata does) takes the family's first entry.
  config.model = !sensor.model.empty() || family == nullptr
                     ? sensor.model
                     : std::string(family->models.front().name);
  if (!sensor.calibration.empty()) config.calibration = sensor.calibration;
  if (!sensor.metadata.empty()) config.metadata = sensor.metadata;
  config.cut = drivers::FrameCut{to_cut_mode(sensor.frame_cut.mode), sensor.frame_cut.azimuth_deg,
                                 sensor.frame_cut.period_s};
  config.settings = sensor.lidar_settings;
  return config;
}

std::vector<ReplayFormat> replay_formats(Driver driver) {
  if (lidar_family(driver) != nullptr) return {ReplayFormat::pcap, ReplayFormat::rosbag1};
  switch (driver) {
    case Driver::v4l2:
    case Driver::aravis:
    case Driver::dataset_camera:
    case Driver::dataset_imu:
      return {ReplayFormat::euroc, ReplayFormat::rosbag1};
    case Driver::can_imu:
      return {ReplayFormat::candump, ReplayFormat::rosbag1};
    case Driver::dataset_lidar:
      return {ReplayFormat::rosbag1};
    default:
      return {};
  }
}

bool supports_udp(Driver driver) {
  return is_packet_lidar(driver);
}

bool supports_device(Driver driver) {
  return driver == Driver::v4l2 || driver == Driver::aravis || driver == Driver::can_imu ||
         driver == Driver::serial_imu;
}

int default_ring_capacity(SensorKind kind) {
  switch (kind) {
    case SensorKind::lidar:
      return 1024;  // packets: 0.5 s of a Mid-360, 1.6 s of an OS1-128 at 1024x10
    case SensorKind::imu:
      return 1024;  // samples: 5 s at 200 Hz
    case SensorKind::camera:
      return 8;  // frames: images are large; a late scheduler drops frames, not memory
  }
  return 1024;
}

}  // namespace livod::daemon
