#pragma once
// Velodyne sensor models supported by the decoder and the per-model wire facts (§4.1 of
// shared/docs/sensor-protocols.md): laser count, distance unit, factory byte, packet rate.

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace livod::drivers::velodyne {

enum class Model : std::uint8_t { kVlp16, kPuckHiRes, kVlp32c, kHdl32e, kVls128 };

// Byte 1204 of a data packet. Other values (HDL-32E firmware before 2.2.20 writes 0) are decoded
// as a single-return packet.
enum class ReturnMode : std::uint8_t { kStrongest = 0x37, kLast = 0x38, kDual = 0x39 };

struct ModelTraits {
  Model model;
  std::string_view name;      // canonical name as used by `livod decode --model`
  int lasers;                 // lasers per firing sequence (16, 32 or 128)
  double distance_unit_m;     // value of one distance LSB on the wire
  std::uint8_t factory_byte;  // byte 1205 this model is expected to report
  double packets_per_second;  // single return, nominal (VROS driver.cc)
  double points_per_second;   // single return, nominal: packets/s x returns per packet
};

[[nodiscard]] const ModelTraits& traits(Model model);

// All supported models, in the order they are listed to users.
[[nodiscard]] std::span<const ModelTraits> all_models();

// Case-insensitive lookup by canonical name ("VLP-16", "HDL-32E", ...); also accepts the names
// without the dash ("VLP16") and "PUCK-HI-RES". nullopt if unknown.
[[nodiscard]] std::optional<Model> model_from_name(std::string_view name);

// The model a factory byte names, if it is one this decoder supports.
[[nodiscard]] std::optional<Model> model_from_factory_byte(std::uint8_t factory_byte);

}  // namespace livod::drivers::velodyne
