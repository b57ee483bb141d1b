#include "drivers/velodyne/model.hpp"

#include "drivers/lidar_family.hpp"

#include <array>
#include <string>

namespace livod::drivers::velodyne {
namespace {

constexpr int kReturnsPerPacket = 12 * 32;

// Packet rates: VROS velodyne_driver/src/driver/driver.cc (single return). Distance units and
// factory bytes: §4.1 (VROS rawdata.h, VDEC types.h).
constexpr std::array<ModelTraits, 5> kModels{{
    {Model::kVlp16, "VLP-16", 16, 0.002, 0x22, 754.0, 754.0 * kReturnsPerPacket},
    {Model::kPuckHiRes, "PUCK-HI-RES", 16, 0.002, 0x24, 754.0, 754.0 * kReturnsPerPacket},
    {Model::kVlp32c, "VLP-32C", 32, 0.004, 0x28, 1507.0, 1507.0 * kReturnsPerPacket},
    {Model::kHdl32e, "HDL-32E", 32, 0.002, 0x21, 1808.0, 1808.0 * kReturnsPerPacket},
    {Model::kVls128, "VLS-128", 128, 0.004, 0xA1, 6253.9, 6253.9 * kReturnsPerPacket},
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
  const std::string wanted = drivers::normalise_model_name(name);
  for (const auto& t : kModels) {
    if (drivers::normalise_model_name(t.name) == wanted) return t.model;
  }
  return std::nullopt;
}

std::optional<Model> model_from_factory_byte(std::uint8_t factory_byte) {
  for (const auto& t : kModels) {
    if (t.factory_byte == factory_byte) return t.model;
  }
  return std::nullopt;
}

}  // namespace livod::drivers::velodyne
