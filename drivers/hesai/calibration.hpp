#pragma once
// Hesai angle correction file: the per-unit CSV that PandarView and the sensor's web interface
// export ("Channel,Elevation,Azimuth" or "Laser id,Elevation,Azimuth", then one row per channel,
// numbered from 1, angles in degrees). The elevation is the beam's vertical angle; the azimuth is
// added to the block azimuth (Hesai's "horizontal angle offset").

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/hesai/model.hpp"

namespace livod::drivers::hesai {

struct ChannelCorrection {
  double elevation_deg = 0.0;
  double azimuth_deg = 0.0;
};

struct AngleCorrections {
  std::vector<ChannelCorrection> channels;  // [channel - 1]
  std::string source;

  // Ring of each channel: its rank by elevation, 0 = lowest beam (ties: lower channel first),
  // the convention of livod's other spinning LiDARs.
  [[nodiscard]] std::vector<std::uint16_t> rings() const;
};

// Throws livod::FormatError (byte offset of the offending line) for text that is not such a
// file: a missing or unknown header, non-numeric fields, channel numbers out of sequence,
// non-finite or impossible angles.
[[nodiscard]] AngleCorrections parse_angle_corrections(std::string_view text,
                                                       const std::string& source);
// Reads the file; throws livod::Error when it cannot be opened.
[[nodiscard]] AngleCorrections load_angle_corrections(const std::filesystem::path& path);

// Throws livod::Error if the file does not describe `model` (channel count).
void check_corrections_match(const AngleCorrections& corrections, Model model);

// The CSV text of `corrections` (what the simulator writes beside its captures).
[[nodiscard]] std::string format_angle_corrections(const AngleCorrections& corrections);

}  // namespace livod::drivers::hesai
