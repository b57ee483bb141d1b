// Metadata parsing on every real metadata file of ouster-sdk's test data (FW 1.12 to 3.2, flat
// and nested layouts) and rejection of every malformed sample with a message naming the problem.

#include "drivers/ouster/metadata.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "tests/support/data_dir.hpp"

namespace livod::drivers::ouster {
namespace {

using Json = nlohmann::json;

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::filesystem::path> good_metadata_files() {
  std::vector<std::filesystem::path> files;
  for (const char* dir : {"ouster/metadata", "ouster/pcaps", "ouster/pcap_with_extrinsics"}) {
    for (const auto& e : std::filesystem::directory_iterator(test::data_path(dir))) {
      const std::string name = e.path().filename().string();
      if (!e.is_regular_file() || e.path().extension() != ".json") continue;
      // Not metadata: ouster-sdk's expected decoder outputs and a multi-sensor extrinsics file.
      if (name.ends_with("_digest.json") || name == "extrinsic_parameters.json") continue;
      files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(OusterMetadata, EveryGoodFileParsesConsistently) {
  const auto files = good_metadata_files();
  ASSERT_GE(files.size(), 50U);
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    SensorMetadata m;
    ASSERT_NO_THROW(m = load_metadata(f));
    const DataFormat& df = m.format;
    EXPECT_EQ(m.beam_altitude_angles_deg.size(), df.pixels_per_column);
    EXPECT_EQ(m.beam_azimuth_angles_deg.size(), df.pixels_per_column);
    EXPECT_EQ(df.pixel_shift_by_row.size(), df.pixels_per_column);
    EXPECT_EQ(df.columns_per_frame % df.columns_per_packet, 0U);
    EXPECT_LT(df.column_window.first, df.columns_per_frame);
    EXPECT_LT(df.column_window.last, df.columns_per_frame);
    EXPECT_GT(m.lidar_origin_to_beam_origin_mm, 0.0);
    EXPECT_DOUBLE_EQ(m.T_lidar_beam_mm(3, 3), 1.0);
    EXPECT_NEAR((m.T_sensor_lidar_mm.topLeftCorner<3, 3>().determinant()), 1.0, 1e-3);

    // Cross-check against the raw JSON, wherever the file keeps these values.
    const Json j = Json::parse(read_text(f));
    const bool nested = j.contains("beam_intrinsics");
    EXPECT_EQ(m.legacy_layout, !nested);
    const Json& beams = nested ? j["beam_intrinsics"] : j;
    EXPECT_DOUBLE_EQ(m.beam_altitude_angles_deg.front(),
                     beams["beam_altitude_angles"].front().get<double>());
    EXPECT_DOUBLE_EQ(m.beam_azimuth_angles_deg.back(),
                     beams["beam_azimuth_angles"].back().get<double>());
    const Json& df_json =
        nested ? j["lidar_data_format"] : (j.contains("data_format") ? j["data_format"] : Json());
    if (df_json.is_object()) {
      EXPECT_EQ(df.pixels_per_column, df_json["pixels_per_column"].get<std::uint32_t>());
      EXPECT_EQ(df.columns_per_frame, df_json["columns_per_frame"].get<std::uint32_t>());
      EXPECT_EQ(df.pixel_shift_by_row, df_json["pixel_shift_by_row"].get<std::vector<int>>());
      if (df_json.contains("udp_profile_lidar")) {
        EXPECT_EQ(to_string(df.udp_profile_lidar), df_json["udp_profile_lidar"].get<std::string>());
      } else {
        EXPECT_EQ(df.udp_profile_lidar, LidarProfile::kLegacy);
      }
    }
    const Json& info = nested ? j["sensor_info"] : j;
    if (info.contains("prod_sn")) {
      EXPECT_EQ(m.prod_sn, info["prod_sn"].get<std::string>());
    }
    if (info.contains("initialization_id")) {
      ASSERT_TRUE(m.initialization_id.has_value());
      EXPECT_EQ(*m.initialization_id, info["initialization_id"].get<std::uint32_t>());
    }
  }
}

TEST(OusterMetadata, EveryMalformedFileIsRejectedWithItsReason) {
  // File -> a fragment the error must contain (JSON path and problem).
  const std::map<std::string, std::string> expected{
      {"complete_but_all_zeros_legacy.json",
       "/beam_altitude_angles: all 128 beam altitude angles are zero"},
      {"garbled_legacy_and_nonlegacy.json",
       "mixes the nested layout (has 'beam_intrinsics') with top-level keys of the legacy flat "
       "layout ('imu_to_sensor_transform', 'data_format'"},
      {"incomplete_data_format_legacy.json",
       "/data_format/columns_per_frame: required key is missing"},
      {"incomplete_data_format_nonlegacy.json",
       "/lidar_data_format/pixels_per_column: required key is missing"},
      {"incomplete_no_calref_nonlegacy.json", "/calibration_status: required key is missing"},
      {"incomplete_no_sensor_info_nonlegacy.json", "/sensor_info: required key is missing"},
      {"incorrect_nbeam_angles_legacy_113.json",
       "/beam_altitude_angles: has 63 angles but beam_azimuth_angles has 64"},
      {"legacy_with_calibration_status.json", "mixes the nested layout (has 'calibration_status')"},
  };
  std::set<std::string> seen;
  for (const auto& e :
       std::filesystem::directory_iterator(test::data_path("ouster/metadata/malformed"))) {
    const std::string name = e.path().filename().string();
    SCOPED_TRACE(name);
    seen.insert(name);
    const auto it = expected.find(name);
    ASSERT_NE(it, expected.end()) << "new malformed sample without an expected reason";
    try {
      (void)load_metadata(e.path());
      ADD_FAILURE() << "accepted";
    } catch (const MetadataError& err) {
      EXPECT_NE(std::string(err.what()).find(it->second), std::string::npos) << err.what();
      EXPECT_NE(std::string(err.what()).find(e.path().string()), std::string::npos)
          << "the message names the file: " << err.what();
    }
  }
  EXPECT_EQ(seen.size(), expected.size());
}

TEST(OusterMetadata, NestedFirmware3Values) {
  const SensorMetadata m =
      load_metadata(test::data_path("ouster/metadata/3_0_1_os-122246000293-128.json"));
  EXPECT_FALSE(m.legacy_layout);
  EXPECT_EQ(m.prod_line, "OS-1-128");
  EXPECT_EQ(m.prod_sn, "122246000293");
  ASSERT_TRUE(m.prod_sn_number.has_value());
  EXPECT_EQ(*m.prod_sn_number, 122246000293ULL);
  ASSERT_TRUE(m.initialization_id.has_value());
  EXPECT_EQ(*m.initialization_id, 1629346U);
  EXPECT_EQ(m.firmware, (FirmwareVersion{3, 0, 1}));
  EXPECT_EQ(m.lidar_mode, "1024x10");
  EXPECT_EQ(m.timestamp_mode, TimestampMode::kInternalOsc);
  EXPECT_EQ(m.udp_port_lidar, std::optional<std::uint16_t>(7502));
  EXPECT_EQ(m.udp_port_imu, std::optional<std::uint16_t>(7503));
  EXPECT_EQ(m.format.udp_profile_lidar, LidarProfile::kRng19Rfl8Sig16Nir16Dual);
  EXPECT_EQ(m.format.udp_profile_imu, ImuProfile::kLegacy);
  EXPECT_EQ(m.format.header_type, HeaderType::kStandard);
  EXPECT_EQ(m.format.pixels_per_column, 128U);
  EXPECT_EQ(m.format.columns_per_frame, 1024U);
  EXPECT_EQ(m.format.columns_per_packet, 16U);
  EXPECT_EQ(m.format.column_window, (ColumnWindow{0, 1023}));
  EXPECT_EQ(m.format.fps, 10U);
  EXPECT_DOUBLE_EQ(m.lidar_origin_to_beam_origin_mm, 16.721);
  EXPECT_DOUBLE_EQ(m.T_lidar_beam_mm(0, 3), 16.721);
  EXPECT_DOUBLE_EQ(m.T_sensor_lidar_mm(2, 3), 38.195);
  EXPECT_DOUBLE_EQ(m.T_sensor_lidar_mm(0, 0), -1.0);
  EXPECT_DOUBLE_EQ(m.T_sensor_imu_mm(1, 3), -9.725);
  EXPECT_NEAR(m.T_sensor_imu_m()(1, 3), -0.009725, 1e-12);
  EXPECT_DOUBLE_EQ(m.T_sensor_imu_m()(0, 0), 1.0);
  EXPECT_TRUE(m.lidar_packets_have_crc());  // FW 3.0.1, standard header
}

TEST(OusterMetadata, LegacyFirmware112GetsDefaults) {
  // FW 1.12 reports neither a data format nor the beam origin offset.
  const SensorMetadata m =
      load_metadata(test::data_path("ouster/metadata/1_12_os1-991937000062-16A0_legacy.json"));
  EXPECT_TRUE(m.legacy_layout);
  EXPECT_EQ(m.format.pixels_per_column, 64U);
  EXPECT_EQ(m.format.columns_per_frame, 1024U);
  EXPECT_EQ(m.format.columns_per_packet, 16U);
  EXPECT_EQ(m.format.column_window, (ColumnWindow{0, 1023}));
  ASSERT_EQ(m.format.pixel_shift_by_row.size(), 64U);
  EXPECT_EQ(std::vector<int>(m.format.pixel_shift_by_row.begin(),
                             m.format.pixel_shift_by_row.begin() + 8),
            (std::vector<int>{18, 12, 6, 0, 18, 12, 6, 0}));
  EXPECT_EQ(m.format.udp_profile_lidar, LidarProfile::kLegacy);
  EXPECT_DOUBLE_EQ(m.lidar_origin_to_beam_origin_mm, 15.806);  // "OS-1-16-A0"
  EXPECT_DOUBLE_EQ(m.T_lidar_beam_mm(0, 3), 15.806);
  EXPECT_EQ(m.firmware, (FirmwareVersion{1, 12, 0}));
  EXPECT_FALSE(m.initialization_id.has_value());
  EXPECT_FALSE(m.lidar_packets_have_crc());

  // The nested FW 1.12 layout stores the TCP API's error reply in place of the data format.
  const SensorMetadata n =
      load_metadata(test::data_path("ouster/metadata/1_12_os1-991913000010-64.json"));
  EXPECT_FALSE(n.legacy_layout);
  EXPECT_EQ(n.format.pixels_per_column, 64U);
  EXPECT_EQ(n.format.columns_per_frame, 1024U);
  EXPECT_EQ(n.udp_port_lidar, std::optional<std::uint16_t>(60823));
}

TEST(OusterMetadata, ReducedConfigUsesDefaultTransforms) {
  const SensorMetadata m =
      load_metadata(test::data_path("ouster/metadata/ouster-studio-reduced-config-v1.json"));
  EXPECT_EQ(m.format.columns_per_frame, 2048U);
  EXPECT_EQ(m.format.pixel_shift_by_row[0], 36);
  EXPECT_DOUBLE_EQ(m.T_sensor_lidar_mm(0, 0), -1.0);
  EXPECT_DOUBLE_EQ(m.T_sensor_lidar_mm(2, 3), 36.18);
  EXPECT_DOUBLE_EQ(m.T_sensor_imu_mm(0, 3), 6.253);
  EXPECT_DOUBLE_EQ(m.lidar_origin_to_beam_origin_mm, 12.163);  // no prod_line: gen-1 default
}

TEST(OusterMetadata, CrcPresenceFollowsFirmwareAndHeader) {
  const auto meta = [](const char* name) {
    return load_metadata(test::data_path(std::string("ouster/pcaps/") + name));
  };
  EXPECT_TRUE(meta("crc_test.json").lidar_packets_have_crc());  // 3.2, RNG15
  EXPECT_FALSE(meta("OS-0-32-U1_v2.2.0_1024x10.json").lidar_packets_have_crc());
  EXPECT_FALSE(meta("duplicate_id.json").lidar_packets_have_crc());            // 2.4
  EXPECT_TRUE(meta("same_ports_nonlegacy.2.json").lidar_packets_have_crc());   // 2.5.2
  EXPECT_FALSE(meta("same_ports_nonlegacy.1.json").lidar_packets_have_crc());  // FUSA header
  EXPECT_EQ(meta("same_ports_nonlegacy.1.json").format.header_type, HeaderType::kFusa);
  EXPECT_FALSE(meta("same_ports_legacy.1.json").lidar_packets_have_crc());  // LEGACY profile
  const SensorMetadata zm = meta("imu_zm_no_lidar_0.json");
  EXPECT_TRUE(zm.imu_packets_have_crc());
  EXPECT_EQ(zm.format.udp_profile_imu, ImuProfile::kAccel32Gyro32Nmea);
  EXPECT_EQ(zm.format.imu_measurements_per_packet, 8U);
  EXPECT_EQ(zm.format.udp_profile_lidar, LidarProfile::kRng19Rfl8Sig16Nir16Zone16);
  EXPECT_EQ(zm.udp_port_lidar, std::optional<std::uint16_t>(0));
  EXPECT_EQ(zm.firmware, (FirmwareVersion{3, 2, 0}));
}

// Edits a real file in memory and expects a rejection naming `fragment`.
void expect_rejected(const std::string& file, const std::function<void(Json&)>& edit,
                     const std::string& fragment) {
  Json j = Json::parse(read_text(test::data_path(file)));
  edit(j);
  try {
    (void)parse_metadata(j.dump(), "edited");
    ADD_FAILURE() << "accepted: " << fragment;
  } catch (const MetadataError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(OusterMetadata, EditedFilesAreRejectedWithThePath) {
  const std::string nested = "ouster/metadata/2_5_0_os-992146000760-128.json";
  expect_rejected(
      nested, [](Json& j) { j["lidar_intrinsics"]["lidar_to_sensor_transform"][0] = 2.0; },
      "/lidar_intrinsics/lidar_to_sensor_transform: rotation part is not a proper rotation");
  expect_rejected(
      nested, [](Json& j) { j["lidar_intrinsics"]["lidar_to_sensor_transform"][15] = 0.0; },
      "bottom row of the 4x4 transform is not (0, 0, 0, 1)");
  expect_rejected(
      nested, [](Json& j) { j["imu_intrinsics"]["imu_to_sensor_transform"].erase(3); },
      "/imu_intrinsics/imu_to_sensor_transform: expected 16 numbers");
  expect_rejected(
      nested, [](Json& j) { j["lidar_data_format"]["pixel_shift_by_row"].erase(0); },
      "/lidar_data_format/pixel_shift_by_row: has 127 entries but pixels_per_column is 128");
  expect_rejected(
      nested, [](Json& j) { j["lidar_data_format"]["column_window"][1] = 1024; },
      "/lidar_data_format/column_window/1: value 1024 is outside [0, 1023]");
  expect_rejected(
      nested, [](Json& j) { j["lidar_data_format"]["udp_profile_lidar"] = "RNG99"; },
      "/lidar_data_format/udp_profile_lidar: unsupported lidar profile 'RNG99'");
  expect_rejected(
      nested, [](Json& j) { j["lidar_data_format"]["columns_per_frame"] = "1024"; },
      "/lidar_data_format/columns_per_frame: expected a non-negative integer, found string");
  expect_rejected(
      nested, [](Json& j) { j["lidar_data_format"]["columns_per_frame"] = 2048; },
      "columns_per_frame 2048 contradicts lidar_mode '1024x10'");
  expect_rejected(
      nested, [](Json& j) { j["beam_intrinsics"]["beam_altitude_angles"][5] = "x"; },
      "/beam_intrinsics/beam_altitude_angles/5: expected a number, found string");
  expect_rejected(
      nested, [](Json& j) { j["beam_intrinsics"]["beam_altitude_angles"].erase(5); },
      "has 127 angles but beam_azimuth_angles has 128");
  expect_rejected(
      nested, [](Json& j) { j["sensor_info"]["initialization_id"] = -1; },
      "/sensor_info/initialization_id: expected a non-negative integer, found -1");
  expect_rejected(
      nested, [](Json& j) { j = Json::array(); }, "metadata must be a JSON object");
  expect_rejected(
      "ouster/metadata/1_12_os1-991937000062-16A0_legacy.json",
      [](Json& j) { j["lidar_mode"] = "999x10"; },
      "/lidar_mode: lidar_mode '999x10' is not one of 512xN, 1024xN, 2048xN");
}

TEST(OusterMetadata, InvalidJsonReportsTheByteOffset) {
  const std::string text =
      read_text(test::data_path("ouster/metadata/2_5_0_os-992146000760-128.json"));
  const std::string truncated = text.substr(0, text.size() / 2);
  try {
    (void)parse_metadata(truncated, "half.json");
    FAIL() << "accepted truncated JSON";
  } catch (const livod::FormatError& e) {
    EXPECT_GE(e.offset(), truncated.size() - 1);
    EXPECT_LE(e.offset(), truncated.size() + 1);
    EXPECT_NE(std::string(e.what()).find("half.json: at byte offset"), std::string::npos);
  }
  EXPECT_THROW((void)load_metadata("/nonexistent/ouster.json"), livod::Error);
  // A number beyond double range is valid JSON syntax but not a value (found by the fuzzer).
  std::string overflow = text;
  const std::size_t at = overflow.find("\"beam_altitude_angles\"");
  ASSERT_NE(at, std::string::npos);
  const std::size_t number = overflow.find('[', at) + 1;
  overflow.insert(number, "1E9999, ");
  try {
    (void)parse_metadata(overflow, "overflow.json");
    FAIL() << "accepted 1E9999";
  } catch (const livod::FormatError& e) {
    EXPECT_EQ(e.offset(), number);
    EXPECT_NE(std::string(e.what()).find("number overflow"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace livod::drivers::ouster
