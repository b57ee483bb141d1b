#pragma once
// Ouster sensor metadata (the JSON the sensor serves at /api/v1/sensor/metadata, or the `.json`
// recorded next to a capture), firmware 1.12 to 3.x.
//
// Two layouts exist: the legacy flat one (beam angles, transforms, `data_format` at the top level;
// FW 1.12-2.x clients) and the nested one (`sensor_info`, `beam_intrinsics`, `lidar_intrinsics`,
// `imu_intrinsics`, `lidar_data_format`, `config_params`, `calibration_status`; FW >= 2.0 HTTP
// API). A file mixing both is rejected, as is any file whose beam calibration, data format or
// transforms are missing, inconsistent or all zero. Every error names the JSON path at fault.
//
// Units are kept as the sensor reports them (degrees, mm) so the struct can be compared with the
// file; the geometry code (xyz_lut.hpp) converts to metres and radians.

#include <Eigen/Core>
#include <compare>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "drivers/ouster/profile.hpp"

namespace livod::drivers::ouster {

// Semantic problem in otherwise well-formed JSON. what() = "<source>: <json path>: <problem>".
class MetadataError : public livod::Error {
 public:
  MetadataError(const std::string& source, const std::string& json_path, const std::string& problem)
      : livod::Error(source + ": " + (json_path.empty() ? std::string("/") : json_path) + ": " +
                     problem),
        json_path_(json_path) {}
  [[nodiscard]] const std::string& json_path() const { return json_path_; }

 private:
  std::string json_path_;
};

// Columns [first, last] inclusive, in measurement_id units. first > last means the window wraps
// through column 0 (e.g. [370, 85] of 512).
struct ColumnWindow {
  std::uint32_t first = 0;
  std::uint32_t last = 0;
  friend bool operator==(const ColumnWindow&, const ColumnWindow&) = default;
};

struct DataFormat {
  std::uint32_t pixels_per_column = 0;   // beams (rows) per column, H
  std::uint32_t columns_per_packet = 0;  // 16 on every released firmware
  std::uint32_t columns_per_frame = 0;   // W (512, 1024, 2048, 4096)
  std::vector<int> pixel_shift_by_row;   // destaggering offsets, one per row
  ColumnWindow column_window;
  LidarProfile udp_profile_lidar = LidarProfile::kLegacy;
  ImuProfile udp_profile_imu = ImuProfile::kLegacy;
  HeaderType header_type = HeaderType::kStandard;
  std::uint32_t imu_measurements_per_packet = 0;  // ACCEL32_GYRO32_NMEA only; 0 = not reported
  std::uint32_t imu_packets_per_frame = 0;        // 0 = not reported
  std::uint32_t fps = 0;                          // frames per second; 0 = not reported
};

struct FirmwareVersion {
  int major = -1;  // -1: not found in image_rev / build_rev
  int minor = 0;
  int patch = 0;
  [[nodiscard]] bool known() const { return major >= 0; }
  friend auto operator<=>(const FirmwareVersion&, const FirmwareVersion&) = default;
};

enum class TimestampMode : std::uint8_t { kUnknown, kInternalOsc, kSyncPulseIn, kPtp1588 };

struct SensorMetadata {
  bool legacy_layout = false;  // true: flat keys (FW 1.x/2.x clients); false: nested

  // sensor_info
  std::string prod_line;                           // "OS-1-128"; legacy FW 1.x: "OS-1-64"
  std::string prod_sn;                             // serial as printed ("122246000293")
  std::optional<std::uint64_t> prod_sn_number;     // when prod_sn is all digits (< 2^40)
  std::optional<std::uint32_t> initialization_id;  // FW >= 2.2; matches lidar packet headers
  std::string prod_pn;
  std::string build_rev;
  std::string image_rev;
  std::string status;
  FirmwareVersion firmware;  // from image_rev ("...-v2.3.0+...") or build_rev ("v2.3.0")

  // config_params
  std::string lidar_mode;  // "1024x10"
  TimestampMode timestamp_mode = TimestampMode::kUnknown;
  std::optional<std::uint16_t> udp_port_lidar;
  std::optional<std::uint16_t> udp_port_imu;

  // Beam intrinsics, one per row (degrees). Azimuth is the offset from the column's encoder angle.
  std::vector<double> beam_altitude_angles_deg;
  std::vector<double> beam_azimuth_angles_deg;
  double lidar_origin_to_beam_origin_mm = 0.0;

  // Row-major 4x4 transforms with translations in millimetres. x_a = T_a_b * x_b:
  //   T_lidar_beam_mm   = beam_intrinsics.beam_to_lidar_transform
  //   T_sensor_lidar_mm = lidar_intrinsics.lidar_to_sensor_transform
  //   T_sensor_imu_mm   = imu_intrinsics.imu_to_sensor_transform
  Eigen::Matrix4d T_lidar_beam_mm = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d T_sensor_lidar_mm = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d T_sensor_imu_mm = Eigen::Matrix4d::Identity();

  DataFormat format;

  // True when lidar packets end in a CRC-64/XZ footer: non-LEGACY, non-FUSA profiles on FW >= 2.5
  // (FW 2.2-2.4 fill the footer with zeros or 0xDEADBEEF/0xC0DE; FUSA headers carry no CRC).
  [[nodiscard]] bool lidar_packets_have_crc() const;
  // Same for IMU and zone packets (only the ACCEL32_GYRO32_NMEA IMU profile has a footer).
  [[nodiscard]] bool imu_packets_have_crc() const;
  // T_sensor_imu with the translation in metres.
  [[nodiscard]] Eigen::Matrix4d T_sensor_imu_m() const;
};

// Parses metadata text. `source` names the input in error messages (a path or "sensor 10.0.0.5").
// Throws livod::FormatError (with the byte offset) for invalid JSON and MetadataError for
// well-formed JSON that is not usable metadata.
[[nodiscard]] SensorMetadata parse_metadata(std::string_view json_text, const std::string& source);

// Reads and parses a metadata file. Throws livod::Error if it cannot be read.
[[nodiscard]] SensorMetadata load_metadata(const std::filesystem::path& path);

// Defaults of firmware that did not report these (ouster-sdk sensor_info.cpp).
[[nodiscard]] double default_lidar_origin_to_beam_origin_mm(std::string_view prod_line);
[[nodiscard]] DataFormat default_data_format(std::uint32_t columns_per_frame);

}  // namespace livod::drivers::ouster
