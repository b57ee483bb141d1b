#include "drivers/lidar_family.hpp"

#include <array>

#include "core/error.hpp"
#include "drivers/hesai/hesai_family.hpp"
#include "drivers/livox/livox_family.hpp"
#include "drivers/ouster/ouster_family.hpp"
#include "drivers/velodyne/velodyne_family.hpp"

namespace livod::drivers {

std::span<const LidarFamily* const> lidar_families() {
  static const std::array<const LidarFamily*, 5> kFamilies{
      &velodyne::velodyne_family(), &ouster::ouster_family(), &livox::livox_sdk1_family(),
      &livox::livox_sdk2_family(), &hesai::hesai_family()};
  return kFamilies;
}

const LidarFamily* find_family(std::string_view driver) {
  for (const LidarFamily* f : lidar_families()) {
    if (f->driver == driver) return f;
  }
  return nullptr;
}

std::optional<ModelMatch> find_model(std::string_view name) {
  for (const LidarFamily* f : lidar_families()) {
    if (const LidarModelInfo* m = f->find_model(name)) return ModelMatch{f, m};
  }
  return std::nullopt;
}

std::string all_model_names() {
  std::string out;
  for (const LidarFamily* f : lidar_families()) {
    if (!out.empty()) out += ", ";
    out += f->model_list();
  }
  return out;
}

std::unique_ptr<LidarDecoder> make_lidar_decoder(const LidarDecoderConfig& config) {
  const auto match = find_model(config.model);
  if (!match) {
    throw Error("unknown model '" + config.model + "'; known models: " + all_model_names());
  }
  return match->family->make_decoder(config);
}

}  // namespace livod::drivers
