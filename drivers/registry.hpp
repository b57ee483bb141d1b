#pragma once
// Model name -> LidarDecoder factory, for the `decode` subcommand, the live sources and replay.
// One table row per model in registry.cpp; a family adds its models by adding rows.

#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "drivers/lidar_decoder.hpp"

namespace livod::drivers {

// What the user supplied to build a decoder. A factory rejects the fields its family does not
// use (with a livod::Error saying so), so that a misplaced option never goes unnoticed.
struct DecoderConfig {
  std::string model;                                 // as typed; matched case-insensitively
  std::optional<std::filesystem::path> calibration;  // Velodyne: VeloView XML or ROS/nebula YAML
  std::optional<std::filesystem::path> metadata;     // Ouster: sensor metadata JSON
};

using DecoderFactory = std::unique_ptr<LidarDecoder> (*)(const DecoderConfig&);

struct DecoderEntry {
  std::string_view model;    // canonical name, e.g. "VLP-16"
  std::string_view family;   // "velodyne", "ouster", "livox"
  std::string_view summary;  // one line for --help and error messages
  DecoderFactory make;
};

// Every model whose driver exists, in the order they are listed to users.
[[nodiscard]] std::span<const DecoderEntry> decoder_entries();

// Case-insensitive; '-', '_' and spaces are ignored ("vlp16" finds "VLP-16"). nullptr if unknown.
[[nodiscard]] const DecoderEntry* find_decoder(std::string_view model);

// "VLP-16, VLP-32C, ..." for messages.
[[nodiscard]] std::string known_models();

// Builds the decoder for config.model. Throws livod::Error for an unknown model (the message
// lists the known ones) and whatever the family's factory throws for bad files or options.
[[nodiscard]] std::unique_ptr<LidarDecoder> make_decoder(const DecoderConfig& config);

}  // namespace livod::drivers
