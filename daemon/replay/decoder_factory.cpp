#include "daemon/replay/decoder_factory.hpp"

#include "core/error.hpp"
#include "daemon/config/sensor_models.hpp"

namespace livod::daemon::replay {

std::unique_ptr<drivers::LidarDecoder> make_lidar_decoder(const SensorConfig& sensor) {
  const drivers::LidarFamily* family = lidar_family(sensor.driver);
  const std::string label = "sensor '" + sensor.name + "' (" +
                            std::string(enum_name(sensor.driver)) + " " + sensor.model + ")";
  if (family == nullptr) throw Error(label + " is not decoded from packets");
  try {
    return family->make_decoder(decoder_config(sensor));
  } catch (const Error& e) {
    throw Error(label + ": " + e.what());
  }
}

}  // namespace livod::daemon::replay
