#pragma once
// One descriptor per LiDAR family: its models (names, aliases, ports, internal IMU and the facts
// that defaults are made of), the frame cuts it can do, the files and configuration section it
// takes, and its decoder factory. The configuration reader, replay, `livod decode`, the daemon
// and the simulator all ask these tables; adding a model touches one family folder
// (drivers/<family>/<family>_family.cpp).
//
// INTERFACE CONTRACT: shared by every family folder, daemon/config, daemon/replay,
// daemon/commands and tools/sim.

#include <array>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/lidar_decoder.hpp"
#include "drivers/lidar_settings.hpp"

namespace livod::drivers {

// Local UDP ports of a sensor's streams; 0 = the family has no such stream.
struct UdpPorts {
  std::uint16_t lidar = 0;     // point packets
  std::uint16_t imu = 0;       // internal IMU (Ouster, Livox; may equal lidar)
  std::uint16_t position = 0;  // Velodyne position/telemetry packets, Hesai GPS packets
  std::uint16_t command = 0;   // Livox host command/control port
  std::uint16_t push = 0;      // Livox SDK2 status push port
};

// What one model is, as far as the rest of livod needs to know. Datasheet figures; an optional
// that is empty is a fact livod has no source for (never guessed).
struct LidarModelInfo {
  std::string_view name;                      // canonical spelling, e.g. "VLP-16", "PANDARXT32"
  std::span<const std::string_view> aliases;  // other accepted spellings
  std::string_view summary;                   // one line for --help and messages
  int beams = 0;                              // lasers / lines / rows; 0 = from the sensor
  double points_per_second = 0.0;             // nominal, single return, default mode
  double scan_rate_hz = 10.0;                 // default frame or rotation rate
  double min_range_m = 0.0;
  double max_range_m = 0.0;
  std::optional<double> range_noise_m;        // datasheet range error (1 sigma where stated)
  std::optional<double> beam_divergence_rad;  // datasheet, the larger axis
  bool internal_imu = false;
  UdpPorts ports;  // host ports of the first unit (vendor defaults)
};

enum class CutMode : std::uint8_t { kAzimuth, kTime, kFrameId };

// Where one scan ends and the next begins.
struct FrameCut {
  CutMode mode = CutMode::kTime;
  double azimuth_deg = 0.0;  // kAzimuth: cut where the azimuth crosses this (0: each turn)
  double period_s = 0.1;     // kTime: scan duration
};

// Which file a family's decoder reads beside the capture.
enum class DecoderFile : std::uint8_t {
  kNone,
  kCalibrationOptional,  // Velodyne: a calibration file, the model's nominal table without one
  kCalibrationRequired,  // Hesai: the unit's angle correction file
  kMetadata,             // Ouster: the sensor metadata JSON
};

// What `livod decode` and the configuration give a family's decoder factory.
struct LidarDecoderConfig {
  std::string model;  // as typed: matched with the aliases, case and separators ignored
  std::optional<std::filesystem::path> calibration;
  std::optional<std::filesystem::path> metadata;
  std::optional<FrameCut> cut;  // nullopt: the family's default
  LidarSettings settings;       // the family's own options (its configuration section)
};
using DecoderConfig = LidarDecoderConfig;  // the name `livod decode`'s registry used

// The configuration reader's view of a family's section, for the family's settings reader.
// Problems are reported by the implementation (with the key's place in the file); a value that
// is absent or invalid comes back empty.
class SettingsReader {
 public:
  virtual ~SettingsReader() = default;
  // [first, second] in degrees, each in [0, 360].
  virtual std::optional<std::array<double, 2>> degree_pair(std::string_view key) = 0;
  virtual std::optional<double> number(std::string_view key, double min, double max) = 0;
  virtual void error(std::string_view key, const std::string& message) = 0;
};

struct LidarFamily {
  std::string_view driver;  // the configuration's `driver:` value
  std::string_view vendor;  // for messages
  std::span<const LidarModelInfo> models;
  bool model_required = true;  // false: the sensor names its model (Ouster metadata)
  std::span<const std::string_view> port_names;  // keys of source.udp.ports
  std::span<const CutMode> cut_modes;            // the first is the default
  DecoderFile file = DecoderFile::kNone;
  // The largest UDP payload of the point stream and of the other streams (IMU, position, GPS):
  // the slot sizes of the live path's packet rings (docs/live-capture.md "Sizing"). Ouster's
  // point packets depend on the metadata (the live source narrows the slot once it has it).
  std::size_t lidar_datagram_bytes = 0;
  std::size_t aux_datagram_bytes = 0;
  // Sensor times that count within a period (Velodyne: microseconds past the hour); 0 = a full
  // time.
  std::int64_t sensor_time_wrap_ns = 0;
  // The family's own configuration section (key = `driver`), read into LidarSettings; nullptr:
  // the family has none.
  void (*read_settings)(SettingsReader& reader, LidarSettings& out) = nullptr;
  // Throws livod::Error for an unknown model, a cut the family cannot do, misplaced files or
  // unusable calibration / metadata.
  std::unique_ptr<LidarDecoder> (*make_decoder)(const LidarDecoderConfig& config) = nullptr;

  // By canonical name or alias, spelling-insensitive (normalise_model_name); nullptr if unknown.
  [[nodiscard]] const LidarModelInfo* find_model(std::string_view name) const;
  [[nodiscard]] bool allows(CutMode mode) const;
  [[nodiscard]] CutMode default_cut() const { return cut_modes.front(); }
  [[nodiscard]] std::string model_list() const;  // "VLP-16, PUCK-HI-RES, ..."
};

// The one spelling-insensitive form of a model name: upper case, '-', '_' and spaces dropped
// ("os-1-64" and "OS1_64" -> "OS164").
[[nodiscard]] inline std::string normalise_model_name(std::string_view name) {
  std::string out;
  out.reserve(name.size());
  for (const char c : name) {
    if (c == '-' || c == '_' || c == ' ') continue;
    out.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  }
  return out;
}

// Header-only, so that the family libraries can use their own descriptor without linking
// livod_drivers (which links them).
inline const LidarModelInfo* LidarFamily::find_model(std::string_view name) const {
  const std::string wanted = normalise_model_name(name);
  for (const LidarModelInfo& m : models) {
    if (normalise_model_name(m.name) == wanted) return &m;
    for (const std::string_view alias : m.aliases) {
      if (normalise_model_name(alias) == wanted) return &m;
    }
  }
  return nullptr;
}

inline bool LidarFamily::allows(CutMode mode) const {
  for (const CutMode m : cut_modes) {
    if (m == mode) return true;
  }
  return false;
}

inline std::string LidarFamily::model_list() const {
  std::string out;
  for (const LidarModelInfo& m : models) {
    if (!out.empty()) out += ", ";
    out += m.name;
  }
  return out;
}

// Every family, in the order they are listed to users.
[[nodiscard]] std::span<const LidarFamily* const> lidar_families();
// By configuration driver name; nullptr if no LiDAR family has it.
[[nodiscard]] const LidarFamily* find_family(std::string_view driver);

struct ModelMatch {
  const LidarFamily* family = nullptr;
  const LidarModelInfo* model = nullptr;
};
// A model of any family, by canonical name or alias; nullopt if unknown.
[[nodiscard]] std::optional<ModelMatch> find_model(std::string_view name);
// "VLP-16, PUCK-HI-RES, ..., PANDAR40P": every model of every family.
[[nodiscard]] std::string all_model_names();

// The decoder of config.model, whichever family has it. Throws livod::Error for an unknown
// model (listing the known ones) and whatever the family's factory throws.
[[nodiscard]] std::unique_ptr<LidarDecoder> make_lidar_decoder(const LidarDecoderConfig& config);

}  // namespace livod::drivers
