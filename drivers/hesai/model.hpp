#pragma once
// Hesai sensor models supported by the decoder and their wire facts, from Hesai's user manuals
// (PandarXT-32: "Data Structure" and Appendix II; Pandar40P: "Data Structure" and Appendix II).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace livod::drivers::hesai {

enum class Model : std::uint8_t { kPandarXT32, kPandar40P };

// How a model's point cloud packet is laid out.
enum class PacketLayout : std::uint8_t {
  // Pre-header (0xEE 0xFF, protocol version), header, blocks of (azimuth, channels x 4 bytes),
  // 24-byte tail, 4-byte UDP sequence (PandarXT, protocol 6.1).
  kPreHeader,
  // Blocks of (0xFFEE flag, azimuth, channels x 3 bytes), 22-byte tail, optional 4-byte UDP
  // sequence (Pandar40P).
  kBlockFlags,
};

struct ModelTraits {
  Model model;
  std::string_view name;  // canonical name as used by `livod decode --model` (Hesai's spelling)
  PacketLayout layout;
  int channels;                     // lasers
  int blocks;                       // blocks per packet
  std::uint8_t protocol_major = 0;  // kPreHeader only
  std::uint8_t protocol_minor = 0;
  std::uint16_t date_year_base;  // the tail's year byte counts from this year
  double firing_round_ns;        // time between firing rounds (one block in single return)
  double distance_unit_m;        // kBlockFlags (the pre-header layout states its own)
  double min_range_m;            // datasheet range
  double max_range_m;
  double points_per_second;  // single return, nominal
};

[[nodiscard]] const ModelTraits& traits(Model model);
[[nodiscard]] std::span<const ModelTraits> all_models();

// Canonical name ("PANDARXT32", "PANDAR40P"), spelling-insensitive (drivers::normalise_model_name;
// aliases: the family table). nullopt if unknown.
[[nodiscard]] std::optional<Model> model_from_name(std::string_view name);

}  // namespace livod::drivers::hesai
