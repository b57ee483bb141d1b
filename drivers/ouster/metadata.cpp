#include "drivers/ouster/metadata.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

namespace livod::drivers::ouster {
namespace {

using Json = nlohmann::json;

// Sections of the nested layout and keys of the flat layout. A file with keys of both kinds is
// ambiguous (ouster-sdk's malformed/garbled_* and legacy_with_calibration_status samples).
constexpr std::array<std::string_view, 8> kNestedSections{
    "sensor_info",       "beam_intrinsics", "lidar_intrinsics",   "imu_intrinsics",
    "lidar_data_format", "config_params",   "calibration_status", "imu_data_format"};
constexpr std::array<std::string_view, 16> kFlatKeys{"beam_altitude_angles",
                                                     "beam_azimuth_angles",
                                                     "beam_to_lidar_transform",
                                                     "lidar_origin_to_beam_origin_mm",
                                                     "lidar_to_sensor_transform",
                                                     "imu_to_sensor_transform",
                                                     "data_format",
                                                     "lidar_mode",
                                                     "prod_sn",
                                                     "prod_line",
                                                     "prod_pn",
                                                     "build_rev",
                                                     "image_rev",
                                                     "initialization_id",
                                                     "udp_port_lidar",
                                                     "udp_port_imu"};

// Transform defaults of firmware that did not report them (ouster-sdk sensor_info.cpp).
constexpr std::array<double, 16> kDefaultLidarToSensor{-1, 0, 0, 0,     0, -1, 0, 0,
                                                       0,  0, 1, 36.18, 0, 0,  0, 1};
constexpr std::array<double, 16> kDefaultImuToSensor{1, 0, 0, 6.253, 0, 1, 0, -11.775,
                                                     0, 0, 1, 7.645, 0, 0, 0, 1};

// Reads values out of the DOM, raising MetadataError with the JSON path on anything unexpected.
class Reader {
 public:
  explicit Reader(const std::string& source) : source_(source) {}

  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw MetadataError(source_, path, problem);
  }

  const Json& require_member(const Json& object, const std::string& path,
                             std::string_view key) const {
    const auto it = object.find(key);
    if (it == object.end()) fail(path + "/" + std::string(key), "required key is missing");
    return *it;
  }

  const Json& require_object(const Json& object, const std::string& path,
                             std::string_view key) const {
    const Json& v = require_member(object, path, key);
    if (!v.is_object()) {
      fail(path + "/" + std::string(key),
           std::string("expected an object, found ") + v.type_name());
    }
    return v;
  }

  static const Json* find(const Json& object, std::string_view key) {
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }

  double number(const Json& v, const std::string& path) const {
    if (!v.is_number()) fail(path, std::string("expected a number, found ") + v.type_name());
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(path, "number is not finite");
    return d;
  }

  std::uint64_t unsigned_integer(const Json& v, const std::string& path, std::uint64_t min,
                                 std::uint64_t max) const {
    if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<std::int64_t>() < 0)) {
      fail(path, std::string("expected a non-negative integer, found ") + describe(v));
    }
    const auto u = v.get<std::uint64_t>();
    if (u < min || u > max) {
      fail(path, "value " + std::to_string(u) + " is outside [" + std::to_string(min) + ", " +
                     std::to_string(max) + "]");
    }
    return u;
  }

  std::string string(const Json& v, const std::string& path) const {
    if (!v.is_string()) fail(path, std::string("expected a string, found ") + v.type_name());
    return v.get<std::string>();
  }

  std::string optional_string(const Json& object, const std::string& path,
                              std::string_view key) const {
    const Json* v = find(object, key);
    if (v == nullptr || v->is_null()) return {};
    return string(*v, path + "/" + std::string(key));
  }

  std::vector<double> number_array(const Json& v, const std::string& path) const {
    if (!v.is_array()) fail(path, std::string("expected an array, found ") + v.type_name());
    std::vector<double> out;
    out.reserve(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      out.push_back(number(v[i], path + "/" + std::to_string(i)));
    }
    return out;
  }

  Eigen::Matrix4d transform(const Json& v, const std::string& path) const {
    const std::vector<double> values = number_array(v, path);
    if (values.size() != 16) {
      fail(path,
           "expected 16 numbers (a row-major 4x4 matrix), found " + std::to_string(values.size()));
    }
    return checked_transform(values, path);
  }

  Eigen::Matrix4d checked_transform(const std::vector<double>& values,
                                    const std::string& path) const {
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = values[static_cast<std::size_t>(r * 4 + c)];
    }
    // A rigid transform: bottom row (0 0 0 1) and an orthonormal rotation. The sensors print
    // rotations with 6 significant digits, hence the tolerance.
    if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
      fail(path, "bottom row of the 4x4 transform is not (0, 0, 0, 1)");
    }
    const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
    const double orthonormality_error = (r.transpose() * r - Eigen::Matrix3d::Identity()).norm();
    if (orthonormality_error > 1e-3 || std::abs(r.determinant() - 1.0) > 1e-3) {
      fail(path, "rotation part is not a proper rotation (|R^T R - I| = " +
                     std::to_string(orthonormality_error) + ")");
    }
    return m;
  }

  static std::string describe(const Json& v) {
    if (v.is_number() || v.is_boolean()) return v.dump();
    return v.type_name();
  }

 private:
  const std::string& source_;
};

std::uint32_t columns_of_lidar_mode(std::string_view mode, std::uint32_t* fps) {
  // "<columns>x<fps>", e.g. "1024x10".
  const auto x = mode.find('x');
  if (x == std::string_view::npos) return 0;
  std::uint32_t columns = 0;
  std::uint32_t rate = 0;
  const auto r1 = std::from_chars(mode.data(), mode.data() + x, columns);
  const auto r2 = std::from_chars(mode.data() + x + 1, mode.data() + mode.size(), rate);
  if (r1.ec != std::errc() || r1.ptr != mode.data() + x || r2.ec != std::errc() ||
      r2.ptr != mode.data() + mode.size() || rate == 0) {
    return 0;
  }
  if (fps != nullptr) *fps = rate;
  return columns;
}

// "ousteros-image-prod-aries-v2.3.0+2022..." or "v2.2.0-rc.2-17-gbc0879e": the first "v" that is
// followed by major.minor.patch.
FirmwareVersion parse_firmware_version(std::string_view text) {
  for (std::size_t i = 0; i + 1 < text.size(); ++i) {
    if (text[i] != 'v' || (i > 0 && text[i - 1] != '-')) continue;
    FirmwareVersion v;
    const char* p = text.data() + i + 1;
    const char* end = text.data() + text.size();
    int* parts[3] = {&v.major, &v.minor, &v.patch};
    bool ok = true;
    for (int k = 0; k < 3 && ok; ++k) {
      const auto r = std::from_chars(p, end, *parts[k]);
      ok = r.ec == std::errc();
      p = r.ptr;
      if (ok && k < 2) {
        ok = p < end && *p == '.';
        ++p;
      }
    }
    if (ok) return v;
  }
  return {};
}

TimestampMode timestamp_mode_from_string(std::string_view s) {
  if (s == "TIME_FROM_INTERNAL_OSC") return TimestampMode::kInternalOsc;
  if (s == "TIME_FROM_SYNC_PULSE_IN") return TimestampMode::kSyncPulseIn;
  if (s == "TIME_FROM_PTP_1588") return TimestampMode::kPtp1588;
  return TimestampMode::kUnknown;
}

constexpr std::uint32_t kMaxPixelsPerColumn = 256;
constexpr std::uint32_t kMaxColumnsPerFrame = 4096;  // 4096x5 is the widest lidar_mode
constexpr std::uint32_t kMaxColumnsPerPacket = 64;
constexpr std::uint32_t kMaxImuMeasurementsPerPacket = 64;

// Parses an explicit data format object (flat `data_format` or nested `lidar_data_format`).
DataFormat parse_data_format(const Reader& rd, const Json& df, const std::string& path) {
  DataFormat f;
  f.pixels_per_column = static_cast<std::uint32_t>(
      rd.unsigned_integer(rd.require_member(df, path, "pixels_per_column"),
                          path + "/pixels_per_column", 1, kMaxPixelsPerColumn));
  f.columns_per_packet = static_cast<std::uint32_t>(
      rd.unsigned_integer(rd.require_member(df, path, "columns_per_packet"),
                          path + "/columns_per_packet", 1, kMaxColumnsPerPacket));
  f.columns_per_frame = static_cast<std::uint32_t>(
      rd.unsigned_integer(rd.require_member(df, path, "columns_per_frame"),
                          path + "/columns_per_frame", 1, kMaxColumnsPerFrame));
  const std::string shift_path = path + "/pixel_shift_by_row";
  const Json& shifts = rd.require_member(df, path, "pixel_shift_by_row");
  if (!shifts.is_array()) {
    rd.fail(shift_path, std::string("expected an array, found ") + shifts.type_name());
  }
  for (std::size_t i = 0; i < shifts.size(); ++i) {
    const Json& s = shifts[i];
    const std::string p = shift_path + "/" + std::to_string(i);
    if (!s.is_number_integer()) rd.fail(p, "expected an integer, found " + Reader::describe(s));
    const auto v = s.get<std::int64_t>();
    if (v < -static_cast<std::int64_t>(f.columns_per_frame) ||
        v > static_cast<std::int64_t>(f.columns_per_frame)) {
      rd.fail(p, "shift " + std::to_string(v) + " exceeds columns_per_frame");
    }
    f.pixel_shift_by_row.push_back(static_cast<int>(v));
  }
  if (const Json* w = Reader::find(df, "column_window"); w != nullptr) {
    const std::string wp = path + "/column_window";
    if (!w->is_array() || w->size() != 2) rd.fail(wp, "expected [first, last]");
    f.column_window.first = static_cast<std::uint32_t>(
        rd.unsigned_integer((*w)[0], wp + "/0", 0, f.columns_per_frame - 1));
    f.column_window.last = static_cast<std::uint32_t>(
        rd.unsigned_integer((*w)[1], wp + "/1", 0, f.columns_per_frame - 1));
  } else {
    f.column_window = {0, f.columns_per_frame - 1};
  }
  if (const Json* p = Reader::find(df, "udp_profile_lidar"); p != nullptr) {
    const std::string name = rd.string(*p, path + "/udp_profile_lidar");
    const auto profile = lidar_profile_from_string(name);
    if (!profile) rd.fail(path + "/udp_profile_lidar", "unsupported lidar profile '" + name + "'");
    f.udp_profile_lidar = *profile;
  }
  if (const Json* p = Reader::find(df, "udp_profile_imu"); p != nullptr) {
    const std::string name = rd.string(*p, path + "/udp_profile_imu");
    const auto profile = imu_profile_from_string(name);
    if (!profile) rd.fail(path + "/udp_profile_imu", "unsupported IMU profile '" + name + "'");
    f.udp_profile_imu = *profile;
  }
  if (const Json* p = Reader::find(df, "header_type"); p != nullptr) {
    const std::string name = rd.string(*p, path + "/header_type");
    const auto header = header_type_from_string(name);
    if (!header) rd.fail(path + "/header_type", "unsupported header type '" + name + "'");
    f.header_type = *header;
  }
  if (const Json* p = Reader::find(df, "fps"); p != nullptr) {
    f.fps = static_cast<std::uint32_t>(rd.unsigned_integer(*p, path + "/fps", 1, 1000));
  }
  return f;
}

void validate_data_format(const Reader& rd, const DataFormat& f, const std::string& path) {
  if (f.columns_per_frame % f.columns_per_packet != 0) {
    rd.fail(path + "/columns_per_frame",
            "columns_per_frame " + std::to_string(f.columns_per_frame) +
                " is not a multiple of columns_per_packet " + std::to_string(f.columns_per_packet));
  }
  if (f.pixel_shift_by_row.size() != f.pixels_per_column) {
    rd.fail(path + "/pixel_shift_by_row", "has " + std::to_string(f.pixel_shift_by_row.size()) +
                                              " entries but pixels_per_column is " +
                                              std::to_string(f.pixels_per_column));
  }
  const bool legacy = f.udp_profile_lidar == LidarProfile::kLegacy;
  const std::size_t column_bytes =
      (legacy ? 20 : 12) +
      f.pixels_per_column * profile_layout(f.udp_profile_lidar).channel_block_size;
  const std::size_t packet_bytes = (legacy ? 0 : 64) + f.columns_per_packet * column_bytes;
  if (packet_bytes > 65507) {  // largest UDP payload over IPv4
    rd.fail(path, "lidar packets would be " + std::to_string(packet_bytes) +
                      " bytes, more than a UDP datagram can hold");
  }
}

struct SectionPaths {
  std::string beam;        // where beam angles live
  std::string lidar_intr;  // lidar_to_sensor_transform
  std::string imu_intr;    // imu_to_sensor_transform
};

void parse_beams(const Reader& rd, const Json& beams, const std::string& path, SensorMetadata& m) {
  m.beam_altitude_angles_deg = rd.number_array(
      rd.require_member(beams, path, "beam_altitude_angles"), path + "/beam_altitude_angles");
  m.beam_azimuth_angles_deg = rd.number_array(rd.require_member(beams, path, "beam_azimuth_angles"),
                                              path + "/beam_azimuth_angles");
  if (m.beam_altitude_angles_deg.size() != m.beam_azimuth_angles_deg.size()) {
    rd.fail(path + "/beam_altitude_angles", "has " +
                                                std::to_string(m.beam_altitude_angles_deg.size()) +
                                                " angles but beam_azimuth_angles has " +
                                                std::to_string(m.beam_azimuth_angles_deg.size()));
  }
  if (m.beam_altitude_angles_deg.empty()) rd.fail(path + "/beam_altitude_angles", "is empty");
  for (std::size_t i = 0; i < m.beam_altitude_angles_deg.size(); ++i) {
    if (std::abs(m.beam_altitude_angles_deg[i]) > 90.0) {
      rd.fail(path + "/beam_altitude_angles/" + std::to_string(i), "altitude beyond +-90 degrees");
    }
    if (std::abs(m.beam_azimuth_angles_deg[i]) > 180.0) {
      rd.fail(path + "/beam_azimuth_angles/" + std::to_string(i), "azimuth beyond +-180 degrees");
    }
  }
  // An uncalibrated or failed sensor reports zeros (ouster-sdk malformed/complete_but_all_zeros):
  // every beam would point at the horizon, which must not reach the estimator.
  const auto is_zero = [](double a) { return a == 0.0; };
  if (std::all_of(m.beam_altitude_angles_deg.begin(), m.beam_altitude_angles_deg.end(), is_zero)) {
    rd.fail(path + "/beam_altitude_angles",
            "all " + std::to_string(m.beam_altitude_angles_deg.size()) +
                " beam altitude angles are zero (the sensor reported no calibration)");
  }
  if (const Json* o = Reader::find(beams, "lidar_origin_to_beam_origin_mm"); o != nullptr) {
    m.lidar_origin_to_beam_origin_mm = rd.number(*o, path + "/lidar_origin_to_beam_origin_mm");
  } else {
    m.lidar_origin_to_beam_origin_mm = default_lidar_origin_to_beam_origin_mm(m.prod_line);
  }
  if (const Json* t = Reader::find(beams, "beam_to_lidar_transform"); t != nullptr) {
    m.T_lidar_beam_mm = rd.transform(*t, path + "/beam_to_lidar_transform");
  } else {
    m.T_lidar_beam_mm = Eigen::Matrix4d::Identity();
    m.T_lidar_beam_mm(0, 3) = m.lidar_origin_to_beam_origin_mm;
  }
}

Eigen::Matrix4d transform_or_default(const Reader& rd, const Json* section, const std::string& path,
                                     std::string_view key, const std::array<double, 16>& fallback) {
  if (section != nullptr) {
    if (const Json* t = Reader::find(*section, key); t != nullptr) {
      return rd.transform(*t, path + "/" + std::string(key));
    }
  }
  return rd.checked_transform(std::vector<double>(fallback.begin(), fallback.end()), path);
}

void parse_sensor_info(const Reader& rd, const Json& info, const std::string& path,
                       SensorMetadata& m) {
  m.prod_line = rd.optional_string(info, path, "prod_line");
  m.prod_pn = rd.optional_string(info, path, "prod_pn");
  m.build_rev = rd.optional_string(info, path, "build_rev");
  m.image_rev = rd.optional_string(info, path, "image_rev");
  m.status = rd.optional_string(info, path, "status");
  if (const Json* sn = Reader::find(info, "prod_sn"); sn != nullptr && !sn->is_null()) {
    if (sn->is_number_unsigned()) {
      m.prod_sn = std::to_string(sn->get<std::uint64_t>());
    } else {
      m.prod_sn = rd.string(*sn, path + "/prod_sn");
    }
    std::uint64_t number = 0;
    const auto r = std::from_chars(m.prod_sn.data(), m.prod_sn.data() + m.prod_sn.size(), number);
    // The packet header carries 40 bits of serial.
    if (!m.prod_sn.empty() && r.ec == std::errc() && r.ptr == m.prod_sn.data() + m.prod_sn.size() &&
        number < (std::uint64_t{1} << 40)) {
      m.prod_sn_number = number;
    }
  }
  if (const Json* id = Reader::find(info, "initialization_id"); id != nullptr && !id->is_null()) {
    m.initialization_id = static_cast<std::uint32_t>(
        rd.unsigned_integer(*id, path + "/initialization_id", 0, (1U << 24) - 1));
  }
  m.firmware = parse_firmware_version(m.image_rev);
  if (!m.firmware.known()) m.firmware = parse_firmware_version(m.build_rev);
}

void parse_config_params(const Reader& rd, const Json& cfg, const std::string& path,
                         SensorMetadata& m) {
  if (const Json* v = Reader::find(cfg, "timestamp_mode"); v != nullptr && v->is_string()) {
    m.timestamp_mode = timestamp_mode_from_string(v->get<std::string>());
  }
  if (const Json* v = Reader::find(cfg, "udp_port_lidar"); v != nullptr && !v->is_null()) {
    m.udp_port_lidar =
        static_cast<std::uint16_t>(rd.unsigned_integer(*v, path + "/udp_port_lidar", 0, 65535));
  }
  if (const Json* v = Reader::find(cfg, "udp_port_imu"); v != nullptr && !v->is_null()) {
    m.udp_port_imu =
        static_cast<std::uint16_t>(rd.unsigned_integer(*v, path + "/udp_port_imu", 0, 65535));
  }
  if (const Json* v = Reader::find(cfg, "lidar_mode"); v != nullptr && !v->is_null()) {
    m.lidar_mode = rd.string(*v, path + "/lidar_mode");
  }
}

// The data format: explicit when the firmware reported one (FW >= 1.14), else the FW 1.12/1.13
// default derived from lidar_mode (64 rows, 16 columns per packet).
DataFormat data_format_or_default(const Reader& rd, const Json* df, const std::string& df_path,
                                  const SensorMetadata& m, const std::string& mode_path) {
  if (df != nullptr && df->is_object()) return parse_data_format(rd, *df, df_path);
  // FW 1.12/1.13 HTTP-less clients store the TCP API's error reply instead of an object.
  if (df != nullptr && !df->is_string() && !df->is_null()) {
    rd.fail(df_path, std::string("expected an object, found ") + df->type_name());
  }
  if (m.lidar_mode.empty()) {
    rd.fail(mode_path, "no data format and no lidar_mode to derive the frame width from");
  }
  const std::uint32_t columns = columns_of_lidar_mode(m.lidar_mode, nullptr);
  if (columns != 512 && columns != 1024 && columns != 2048) {
    rd.fail(mode_path, "lidar_mode '" + m.lidar_mode + "' is not one of 512xN, 1024xN, 2048xN");
  }
  return default_data_format(columns);
}

void finish(const Reader& rd, SensorMetadata& m, const std::string& df_path,
            const std::string& beam_path, const Json* imu_data_format,
            const std::string& imu_df_path) {
  if (imu_data_format != nullptr && imu_data_format->is_object()) {
    if (const Json* v = Reader::find(*imu_data_format, "imu_measurements_per_packet")) {
      m.format.imu_measurements_per_packet = static_cast<std::uint32_t>(rd.unsigned_integer(
          *v, imu_df_path + "/imu_measurements_per_packet", 1, kMaxImuMeasurementsPerPacket));
    }
    if (const Json* v = Reader::find(*imu_data_format, "imu_packets_per_frame")) {
      m.format.imu_packets_per_frame = static_cast<std::uint32_t>(
          rd.unsigned_integer(*v, imu_df_path + "/imu_packets_per_frame", 1, 1000));
    }
  }
  // The FUSA profile always comes with the FUSA header, whether or not header_type is listed.
  if (m.format.udp_profile_lidar == LidarProfile::kFusaRng15Rfl8Nir8Dual) {
    m.format.header_type = HeaderType::kFusa;
  }
  validate_data_format(rd, m.format, df_path);
  if (m.beam_altitude_angles_deg.size() != m.format.pixels_per_column) {
    rd.fail(beam_path + "/beam_altitude_angles",
            "has " + std::to_string(m.beam_altitude_angles_deg.size()) +
                " beams but the data format has " + std::to_string(m.format.pixels_per_column) +
                " pixels per column");
  }
  std::uint32_t fps = 0;
  const std::uint32_t mode_columns = columns_of_lidar_mode(m.lidar_mode, &fps);
  if (m.format.fps == 0) m.format.fps = fps;
  if (mode_columns != 0 && mode_columns != m.format.columns_per_frame) {
    rd.fail(df_path + "/columns_per_frame", "columns_per_frame " +
                                                std::to_string(m.format.columns_per_frame) +
                                                " contradicts lidar_mode '" + m.lidar_mode + "'");
  }
}

SensorMetadata parse_flat(const Reader& rd, const Json& root) {
  SensorMetadata m;
  m.legacy_layout = true;
  parse_sensor_info(rd, root, "", m);
  parse_config_params(rd, root, "", m);
  parse_beams(rd, root, "", m);
  m.T_sensor_lidar_mm =
      transform_or_default(rd, &root, "", "lidar_to_sensor_transform", kDefaultLidarToSensor);
  m.T_sensor_imu_mm =
      transform_or_default(rd, &root, "", "imu_to_sensor_transform", kDefaultImuToSensor);
  m.format = data_format_or_default(rd, Reader::find(root, "data_format"), "/data_format", m,
                                    "/lidar_mode");
  finish(rd, m, "/data_format", "", nullptr, "");
  return m;
}

SensorMetadata parse_nested(const Reader& rd, const Json& root) {
  SensorMetadata m;
  m.legacy_layout = false;
  // Every firmware with the nested layout reports all of these; a file without one of them was
  // cut short (ouster-sdk malformed/incomplete_* samples).
  const Json& info = rd.require_object(root, "", "sensor_info");
  const Json& beams = rd.require_object(root, "", "beam_intrinsics");
  const Json& lidar_intrinsics = rd.require_object(root, "", "lidar_intrinsics");
  const Json& imu_intrinsics = rd.require_object(root, "", "imu_intrinsics");
  const Json& config = rd.require_object(root, "", "config_params");
  rd.require_member(root, "", "lidar_data_format");
  rd.require_member(root, "", "calibration_status");

  parse_sensor_info(rd, info, "/sensor_info", m);
  parse_config_params(rd, config, "/config_params", m);
  parse_beams(rd, beams, "/beam_intrinsics", m);
  m.T_sensor_lidar_mm = rd.transform(
      rd.require_member(lidar_intrinsics, "/lidar_intrinsics", "lidar_to_sensor_transform"),
      "/lidar_intrinsics/lidar_to_sensor_transform");
  m.T_sensor_imu_mm =
      rd.transform(rd.require_member(imu_intrinsics, "/imu_intrinsics", "imu_to_sensor_transform"),
                   "/imu_intrinsics/imu_to_sensor_transform");
  m.format = data_format_or_default(rd, Reader::find(root, "lidar_data_format"),
                                    "/lidar_data_format", m, "/config_params/lidar_mode");
  finish(rd, m, "/lidar_data_format", "/beam_intrinsics", Reader::find(root, "imu_data_format"),
         "/imu_data_format");
  return m;
}

// Byte offset of the token quoted in an nlohmann message ("... parsing '<token>'"), or 0.
std::uint64_t offending_token_offset(std::string_view text, std::string_view message) {
  constexpr std::string_view kMarker = "parsing '";
  const auto start = message.find(kMarker);
  if (start == std::string_view::npos) return 0;
  const auto token_begin = start + kMarker.size();
  const auto token_end = message.find('\'', token_begin);
  if (token_end == std::string_view::npos || token_end == token_begin) return 0;
  const auto pos = text.find(message.substr(token_begin, token_end - token_begin));
  return pos == std::string_view::npos ? 0 : pos;
}

}  // namespace

bool SensorMetadata::lidar_packets_have_crc() const {
  if (format.udp_profile_lidar == LidarProfile::kLegacy) return false;
  if (format.header_type == HeaderType::kFusa) return false;
  return firmware.known() && firmware >= FirmwareVersion{2, 5, 0};
}

bool SensorMetadata::imu_packets_have_crc() const {
  if (format.udp_profile_imu == ImuProfile::kLegacy) return false;
  if (format.header_type == HeaderType::kFusa) return false;
  return firmware.known() && firmware >= FirmwareVersion{2, 5, 0};
}

Eigen::Matrix4d SensorMetadata::T_sensor_imu_m() const {
  Eigen::Matrix4d t = T_sensor_imu_mm;
  t.topRightCorner<3, 1>() *= 1e-3;
  return t;
}

double default_lidar_origin_to_beam_origin_mm(std::string_view prod_line) {
  if (prod_line.rfind("OS-0-", 0) == 0) return 27.67;
  if (prod_line.rfind("OS-1-", 0) == 0) return 15.806;
  if (prod_line.rfind("OS-2-", 0) == 0) return 13.762;
  return 12.163;  // first-generation OS-1 ("OS1-64")
}

DataFormat default_data_format(std::uint32_t columns_per_frame) {
  DataFormat f;
  f.pixels_per_column = 64;
  f.columns_per_packet = 16;
  f.columns_per_frame = columns_per_frame;
  f.column_window = {0, columns_per_frame - 1};
  // Gen-1 64-beam staggering: rows repeat in groups of four, shifted by 9/6/3/0 columns at
  // 512 columns per frame and proportionally more at 1024 and 2048.
  const int step = static_cast<int>(columns_per_frame / 512) * 3;
  for (int i = 0; i < 64; ++i) f.pixel_shift_by_row.push_back(step * (3 - i % 4));
  return f;
}

SensorMetadata parse_metadata(std::string_view json_text, const std::string& source) {
  Json root;
  try {
    root = Json::parse(json_text.begin(), json_text.end());
  } catch (const Json::parse_error& e) {
    throw livod::FormatError(source, e.byte, std::string("invalid JSON: ") + e.what());
  } catch (const Json::exception& e) {
    // Syntactically valid but unrepresentable, e.g. a number like 1E9999 (nlohmann reports
    // "number overflow parsing '<token>'" without a position): locate the token ourselves.
    throw livod::FormatError(source, offending_token_offset(json_text, e.what()),
                             std::string("invalid JSON: ") + e.what());
  }
  const Reader rd(source);
  if (!root.is_object()) {
    rd.fail("", std::string("metadata must be a JSON object, found ") + root.type_name());
  }
  std::string nested_found;
  std::string flat_found;
  for (std::string_view key : kNestedSections) {
    if (root.contains(key) && nested_found.empty()) nested_found = key;
  }
  for (std::string_view key : kFlatKeys) {
    if (root.contains(key))
      flat_found += (flat_found.empty() ? "'" : ", '") + std::string(key) + "'";
  }
  if (!nested_found.empty() && !flat_found.empty()) {
    rd.fail("", "mixes the nested layout (has '" + nested_found +
                    "') with top-level keys of the legacy flat layout (" + flat_found + ")");
  }
  return nested_found.empty() ? parse_flat(rd, root) : parse_nested(rd, root);
}

SensorMetadata load_metadata(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw livod::Error("cannot open Ouster metadata file " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw livod::Error("cannot read Ouster metadata file " + path.string());
  return parse_metadata(text.str(), path.string());
}

}  // namespace livod::drivers::ouster
