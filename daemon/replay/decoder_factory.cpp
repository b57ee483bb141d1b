#include "daemon/replay/decoder_factory.hpp"

#include <cmath>

#include "core/error.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "drivers/ouster/ouster_factory.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"

namespace livod::daemon::replay {
namespace {

std::int64_t period_ns(const FrameCutConfig& cut) {
  return static_cast<std::int64_t>(std::llround(cut.period_s * 1e9));
}

std::string label(const SensorConfig& sensor) {
  return "sensor '" + sensor.name + "' (" + std::string(enum_name(sensor.driver)) + " " +
         sensor.model + ")";
}

std::unique_ptr<drivers::LidarDecoder> make_velodyne(const SensorConfig& sensor) {
  namespace vd = drivers::velodyne;
  const auto model = vd::model_from_name(sensor.model);
  if (!model) throw Error(label(sensor) + ": the Velodyne decoder does not know this model");
  vd::VelodyneOptions options;
  options.model = *model;
  if (!sensor.calibration.empty()) options.calibration_file = sensor.calibration;
  switch (sensor.frame_cut.mode) {
    case FrameCutMode::azimuth:
      options.cut = sensor.frame_cut.azimuth_deg == 0.0 ? vd::ScanCut::kAzimuthDecrease
                                                        : vd::ScanCut::kAzimuthAngle;
      options.cut_angle_deg = sensor.frame_cut.azimuth_deg;
      break;
    case FrameCutMode::time:
      options.cut = vd::ScanCut::kTimePeriod;
      options.cut_period_ns = period_ns(sensor.frame_cut);
      break;
    case FrameCutMode::frame_id:
      throw Error(label(sensor) +
                  ": Velodyne packets carry no frame id (frame_cut azimuth or time)");
  }
  return std::make_unique<vd::VelodyneDecoder>(options);
}

std::unique_ptr<drivers::LidarDecoder> make_ouster(const SensorConfig& sensor) {
  if (sensor.frame_cut.mode != FrameCutMode::frame_id) {
    throw Error(label(sensor) + ": the Ouster decoder cuts scans by frame id only (frame_cut: " +
                "{mode: frame_id})");
  }
  if (sensor.metadata.empty()) {
    throw Error(label(sensor) + ": replay needs the sensor metadata JSON ('metadata')");
  }
  drivers::DecoderConfig config;
  config.model = "OS";
  config.metadata = sensor.metadata;
  return drivers::ouster::make_ouster_decoder(config);
}

std::unique_ptr<drivers::LidarDecoder> make_livox(const SensorConfig& sensor) {
  const auto model = livox::livox_model(sensor.model);
  if (!model) throw Error(label(sensor) + ": the Livox decoder does not know this model");
  livox::LivoxDecoderOptions options;
  options.scan_period_ns = period_ns(sensor.frame_cut);
  return std::make_unique<livox::LivoxDecoder>(*model, options);
}

}  // namespace

std::unique_ptr<drivers::LidarDecoder> make_lidar_decoder(const SensorConfig& sensor) {
  switch (sensor.driver) {
    case Driver::velodyne:
      return make_velodyne(sensor);
    case Driver::ouster:
      return make_ouster(sensor);
    case Driver::livox_sdk1:
    case Driver::livox_sdk2:
      return make_livox(sensor);
    default:
      throw Error(label(sensor) + " is not decoded from packets");
  }
}

}  // namespace livod::daemon::replay
