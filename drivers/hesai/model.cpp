#include "drivers/hesai/model.hpp"

#include <array>

#include "drivers/lidar_family.hpp"

namespace livod::drivers::hesai {
namespace {

// PandarXT-32: 32 channels, 8 blocks, a firing round every 50 us (20 kHz), 4 mm distance unit
// (stated in the header), years counted from 1900. Pandar40P: 40 channels, 10 blocks, a firing
// round every 55.56 us (18 kHz at 10 Hz), 4 mm, years from 2000.
constexpr std::array<ModelTraits, 2> kModels{{
    {Model::kPandarXT32, "PANDARXT32", PacketLayout::kPreHeader, 32, 8, 6, 1, 1900, 50'000.0, 0.004,
     32 * 20'000.0},
    {Model::kPandar40P, "PANDAR40P", PacketLayout::kBlockFlags, 40, 10, 0, 0, 2000, 55'560.0, 0.004,
     40 * 18'000.0},
}};

}  // namespace

const ModelTraits& traits(Model model) {
  for (const auto& t : kModels) {
    if (t.model == model) return t;
  }
  return kModels[0];  // unreachable: every enumerator has an entry
}

std::span<const ModelTraits> all_models() {
  return kModels;
}

std::optional<Model> model_from_name(std::string_view name) {
  for (const auto& t : kModels) {
    if (normalise_model_name(t.name) == normalise_model_name(name)) return t.model;
  }
  return std::nullopt;
}

}  // namespace livod::drivers::hesai
