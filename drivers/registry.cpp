#include "drivers/registry.hpp"

#include <array>
#include <cctype>

#include "core/error.hpp"
#include "drivers/livox/livox_factory.hpp"
#include "drivers/ouster/ouster_factory.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"

namespace livod::drivers {
namespace {

std::string normalised(std::string_view name) {
  std::string out;
  for (const char c : name) {
    if (c == '-' || c == '_' || c == ' ') continue;
    out.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  }
  return out;
}

std::unique_ptr<LidarDecoder> make_velodyne(velodyne::Model model, const DecoderConfig& config) {
  if (config.metadata) {
    throw Error("--metadata is for Ouster sensors; the " + config.model +
                " takes a calibration file (--calibration)");
  }
  velodyne::VelodyneOptions options;
  options.model = model;
  options.calibration_file = config.calibration;
  return std::make_unique<velodyne::VelodyneDecoder>(options);
}

template <velodyne::Model kModel>
std::unique_ptr<LidarDecoder> make_velodyne_model(const DecoderConfig& config) {
  return make_velodyne(kModel, config);
}

}  // namespace

std::span<const DecoderEntry> decoder_entries() {
  using velodyne::Model;
  static constexpr std::array kEntries{
      DecoderEntry{"VLP-16", "velodyne", "Velodyne VLP-16 (Puck)",
                   &make_velodyne_model<Model::kVlp16>},
      DecoderEntry{"PUCK-HI-RES", "velodyne", "Velodyne Puck Hi-Res",
                   &make_velodyne_model<Model::kPuckHiRes>},
      DecoderEntry{"VLP-32C", "velodyne", "Velodyne VLP-32C (Ultra Puck)",
                   &make_velodyne_model<Model::kVlp32c>},
      DecoderEntry{"HDL-32E", "velodyne", "Velodyne HDL-32E (with its IMU)",
                   &make_velodyne_model<Model::kHdl32e>},
      DecoderEntry{"VLS-128", "velodyne", "Velodyne VLS-128 (Alpha Prime)",
                   &make_velodyne_model<Model::kVls128>},
      DecoderEntry{"OS", "ouster", "Ouster OS0/OS1/OS2, any profile (needs --metadata)",
                   &ouster::make_ouster_decoder},
      DecoderEntry{"AVIA", "livox", "Livox Avia (SDK1)", &livox::make_livox_decoder},
      DecoderEntry{"HORIZON", "livox", "Livox Horizon (SDK1)", &livox::make_livox_decoder},
      DecoderEntry{"TELE-15", "livox", "Livox Tele-15 (SDK1)", &livox::make_livox_decoder},
      DecoderEntry{"MID-40", "livox", "Livox Mid-40 (SDK1)", &livox::make_livox_decoder},
      DecoderEntry{"MID-70", "livox", "Livox Mid-70 (SDK1)", &livox::make_livox_decoder},
      DecoderEntry{"MID-360", "livox", "Livox Mid-360 (SDK2)", &livox::make_livox_decoder},
      DecoderEntry{"HAP", "livox", "Livox HAP (SDK2)", &livox::make_livox_decoder},
      // Other families: one row per model.
  };
  return kEntries;
}

const DecoderEntry* find_decoder(std::string_view model) {
  const std::string wanted = normalised(model);
  for (const auto& entry : decoder_entries()) {
    if (normalised(entry.model) == wanted) return &entry;
  }
  return nullptr;
}

std::string known_models() {
  std::string out;
  for (const auto& entry : decoder_entries()) {
    if (!out.empty()) out += ", ";
    out += entry.model;
  }
  return out;
}

std::unique_ptr<LidarDecoder> make_decoder(const DecoderConfig& config) {
  const DecoderEntry* entry = find_decoder(config.model);
  if (entry == nullptr) {
    throw Error("unknown model '" + config.model + "'; known models: " + known_models());
  }
  return entry->make(config);
}

}  // namespace livod::drivers
