#include "drivers/ouster/ouster_factory.hpp"

#include "core/error.hpp"
#include "drivers/ouster/ouster_decoder.hpp"

namespace livod::drivers::ouster {

std::unique_ptr<LidarDecoder> make_ouster_decoder(const DecoderConfig& config) {
  if (config.calibration) {
    throw livod::Error("--calibration is for Velodyne and Hesai sensors; an Ouster sensor (" +
                       config.model + ") takes its metadata JSON (--metadata)");
  }
  if (!config.metadata) {
    throw livod::Error("an Ouster sensor (" + config.model +
                       ") needs its metadata JSON (--metadata): the file recorded next to the "
                       "capture, or GET http://<sensor>/api/v1/sensor/metadata");
  }
  return std::make_unique<OusterDecoder>(load_metadata(*config.metadata));
}

}  // namespace livod::drivers::ouster
