#include "daemon/replay/decoder_factory.hpp"

#include "core/error.hpp"
#include "daemon/config/sensor_models.hpp"
#include "drivers/ouster/ouster_factory.hpp"

namespace livod::daemon::replay {
namespace {

std::string label(const SensorConfig& sensor) {
  return "sensor '" + sensor.name + "' (" + std::string(enum_name(sensor.driver)) + " " +
         sensor.model + ")";
}

}  // namespace

std::string ouster_model_mismatch(const SensorConfig& sensor,
                                  const drivers::ouster::SensorMetadata& metadata) {
  return drivers::ouster::model_mismatch(sensor.model, metadata);
}

std::unique_ptr<drivers::LidarDecoder> make_ouster_decoder(
    const SensorConfig& sensor, const drivers::ouster::SensorMetadata& metadata) {
  try {
    return drivers::ouster::make_ouster_decoder(decoder_config(sensor), metadata);
  } catch (const Error& e) {
    throw Error(label(sensor) + ": " + e.what());
  }
}

std::unique_ptr<drivers::LidarDecoder> make_lidar_decoder(const SensorConfig& sensor) {
  const drivers::LidarFamily* family = lidar_family(sensor.driver);
  if (family == nullptr) throw Error(label(sensor) + " is not decoded from packets");
  try {
    return family->make_decoder(decoder_config(sensor));
  } catch (const Error& e) {
    throw Error(label(sensor) + ": " + e.what());
  }
}

}  // namespace livod::daemon::replay
