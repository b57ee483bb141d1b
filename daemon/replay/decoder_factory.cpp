#include "daemon/replay/decoder_factory.hpp"

#include <cmath>

#include "core/error.hpp"
#include "daemon/config/sensor_models.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
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

void check_ouster_frame_cut(const SensorConfig& sensor) {
  if (sensor.frame_cut.mode != FrameCutMode::frame_id) {
    throw Error(label(sensor) + ": the Ouster decoder cuts scans by frame id only (frame_cut: " +
                "{mode: frame_id})");
  }
}

std::unique_ptr<drivers::LidarDecoder> make_ouster(const SensorConfig& sensor) {
  check_ouster_frame_cut(sensor);
  if (sensor.metadata.empty()) {
    throw Error(label(sensor) + ": replay needs the sensor metadata JSON ('metadata')");
  }
  return make_ouster_decoder(sensor, drivers::ouster::load_metadata(sensor.metadata));
}

std::unique_ptr<drivers::LidarDecoder> make_livox(const SensorConfig& sensor) {
  const auto model = livox::livox_model(sensor.model);
  if (!model) throw Error(label(sensor) + ": the Livox decoder does not know this model");
  livox::LivoxDecoderOptions options;
  options.scan_period_ns = period_ns(sensor.frame_cut);
  return std::make_unique<livox::LivoxDecoder>(*model, options);
}

}  // namespace

std::string ouster_model_mismatch(const SensorConfig& sensor,
                                  const drivers::ouster::SensorMetadata& metadata) {
  if (sensor.model.empty()) return {};
  const auto configured = canonical_model(Driver::ouster, sensor.model);
  const auto recorded = canonical_model(Driver::ouster, metadata.prod_line);
  const std::size_t beams = metadata.beam_altitude_angles_deg.size();
  std::string configured_beams;
  if (configured) configured_beams = configured->substr(configured->rfind('-') + 1);
  if (recorded && configured && *recorded != *configured) {
    return "model " + *configured + " contradicts the metadata, which describes an " +
           metadata.prod_line + " (" + std::to_string(beams) + " beams)";
  }
  if (configured && !configured_beams.empty() && configured_beams != std::to_string(beams)) {
    return "model " + *configured + " (" + configured_beams +
           " beams) contradicts the metadata, which has " + std::to_string(beams) + " beams";
  }
  return {};
}

std::unique_ptr<drivers::LidarDecoder> make_ouster_decoder(
    const SensorConfig& sensor, const drivers::ouster::SensorMetadata& metadata) {
  check_ouster_frame_cut(sensor);
  if (const std::string mismatch = ouster_model_mismatch(sensor, metadata); !mismatch.empty()) {
    throw Error(label(sensor) + ": " + mismatch);
  }
  return std::make_unique<drivers::ouster::OusterDecoder>(metadata);
}

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
