#include "drivers/ouster/ouster_factory.hpp"

#include "core/error.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "drivers/ouster/ouster_family.hpp"

namespace livod::drivers::ouster {

std::string model_mismatch(std::string_view model, const SensorMetadata& metadata) {
  const LidarFamily& family = ouster_family();
  const LidarModelInfo* configured = family.find_model(model);
  if (configured == nullptr || configured->beams == 0) return {};
  const LidarModelInfo* recorded = family.find_model(metadata.prod_line);
  const std::size_t beams = metadata.beam_altitude_angles_deg.size();
  if (recorded != nullptr && recorded != configured) {
    return "model " + std::string(configured->name) +
           " contradicts the metadata, which describes an " + metadata.prod_line + " (" +
           std::to_string(beams) + " beams)";
  }
  if (static_cast<std::size_t>(configured->beams) != beams) {
    return "model " + std::string(configured->name) + " (" + std::to_string(configured->beams) +
           " beams) contradicts the metadata, which has " + std::to_string(beams) + " beams";
  }
  return {};
}

std::unique_ptr<LidarDecoder> make_ouster_decoder(const DecoderConfig& config,
                                                  const SensorMetadata& metadata) {
  if (config.cut && config.cut->mode != CutMode::kFrameId) {
    throw livod::Error(
        "the Ouster decoder cuts scans by frame id only (frame_cut: {mode: frame_id})");
  }
  if (config.calibration) {
    throw livod::Error("--calibration is for Velodyne and Hesai sensors; an Ouster sensor (" +
                       config.model + ") takes its metadata JSON (--metadata)");
  }
  if (const std::string mismatch = model_mismatch(config.model, metadata); !mismatch.empty()) {
    throw livod::Error(mismatch);
  }
  return std::make_unique<OusterDecoder>(metadata);
}

std::unique_ptr<LidarDecoder> make_ouster_decoder(const DecoderConfig& config) {
  if (!config.metadata) {
    throw livod::Error("an Ouster sensor (" + config.model +
                       ") needs its metadata JSON (--metadata): the file recorded next to the "
                       "capture, or GET http://<sensor>/api/v1/sensor/metadata");
  }
  return make_ouster_decoder(config, load_metadata(*config.metadata));
}

}  // namespace livod::drivers::ouster
