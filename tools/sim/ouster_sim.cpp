#include "tools/sim/ouster_sim.hpp"

#include "core/units.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <random>
#include <span>
#include <string_view>
#include <type_traits>

#include "core/error.hpp"
#include "drivers/ouster/crc64.hpp"
#include "tools/sim/lidar_return.hpp"

namespace livod::sim {
namespace {

static_assert(std::endian::native == std::endian::little,
              "packet fields are written with memcpy into the little-endian wire format");

// Lidar mode 1024x10 with profile RNG19_RFL8_SIG16_NIR16 (sensor-protocols.md §3.3).
constexpr std::uint32_t kColumnsPerFrame = 1024;
constexpr std::uint32_t kColumnsPerPacket = 16;
constexpr std::size_t kPacketHeaderBytes = 32;
constexpr std::size_t kPacketFooterBytes = 32;
constexpr std::size_t kCrcBytes = 8;
constexpr std::size_t kColumnHeaderBytes = 12;  // ts u64, measurement_id u16, status u16
constexpr std::size_t kChannelBlockBytes = 12;
constexpr std::uint32_t kMaxWireRangeMm = (1U << 19) - 1;  // RANGE is 19 bits
constexpr std::uint16_t kLidarPacketType = 1;
constexpr std::uint16_t kColumnStatusValid = 1;
constexpr std::size_t kLegacyImuPacketBytes = 48;
constexpr std::uint16_t kLidarPort = 7502;
constexpr std::uint16_t kImuPort = 7503;
constexpr double kDegreesPerRadian = 180.0 / std::numbers::pi;

// LEGACY IMU stamps of a real OS1 (OS-1-64_1024x10_fw20.pcap): sys_ts ticks exactly every 10 ms,
// accel_ts and gyro_ts follow it by these amounts.
constexpr std::int64_t kImuAccelAfterSysNs = 213'920;
constexpr std::int64_t kImuGyroAfterSysNs = 435'300;

// frame_id is 16 bits on the wire; starting near the top makes every run longer than 4.2 s cross
// the wrap-around (frame 42 has id 0), which decoders must handle (a real sensor wraps every
// 109 minutes at 10 Hz, so a short capture would never show it).
constexpr std::uint32_t kFirstFrameId = 65'494;

// OS1 calibration constants (ouster-sdk's OS-1 defaults and e.g. ouster-sdk's metadata file
// 2_5_0_os-992146000760-128.json; other OS1 revisions differ by a few mm): beam origin
// 15.806 mm from the lidar axis, lidar frame 36.18 mm above the sensor frame and turned by 180
// degrees about z, IMU at (6.253, -11.775, 7.645) mm in the sensor frame.
constexpr double kBeamOriginMm = 15.806;
constexpr double kLidarAboveSensorMm = 36.18;
constexpr std::array<double, 3> kImuInSensorMm{6.253, -11.775, 7.645};

// What distinguishes the simulated products.
struct Product {
  const char* prod_line;  // sensor_info.prod_line
  const char* prod_pn;
  const char* prod_sn;  // digits, < 2^40 (the packet header carries 40 bits)
  std::uint32_t rows;
};

constexpr Product kOs1_64{"OS-1-64", "840-103574-06", "992209000164", 64};
constexpr Product kOs1_128{"OS-1-128", "840-103575-06", "992209000128", 128};

struct BeamCalibration {
  std::vector<double> altitude_deg;
  std::vector<double> azimuth_deg;
  std::vector<int> pixel_shift_by_row;
};

// Metadata prints angles with two decimals; the simulator uses exactly the printed values so
// that its rays and the decoder's agree.
double round_to_hundredths(double deg) {
  return std::round(deg * 100.0) / 100.0;
}

// Beam angles shaped like real OS1 (rev 6/7) metadata: altitudes nearly uniform over the vertical
// field of view (+-22.5 deg) with irregularities of a few hundredths of a degree; azimuth offsets
// repeating in groups of four (the four detector columns: about +4.23, +1.42, -1.42, -4.23 deg)
// with per-beam deviations of ~0.02 deg. pixel_shift_by_row is what the firmware derives from
// them, round(azimuth * W / 360), which gives the 12, 4, -4, -12 of real 1024-column files.
BeamCalibration os1_beams(std::uint32_t rows) {
  constexpr double kHalfFovDeg = 22.5;
  constexpr std::array<double, 4> kStaggerDeg{4.23, 1.42, -1.42, -4.23};
  BeamCalibration b;
  for (std::uint32_t u = 0; u < rows; ++u) {
    const double k = static_cast<double>(u);
    const double alt = kHalfFovDeg - 2.0 * kHalfFovDeg * k / static_cast<double>(rows - 1) +
                       0.03 * std::sin(1.7 * k + 0.4);
    const double az = kStaggerDeg[u % 4] + 0.02 * std::sin(0.9 * k + 1.1);
    b.altitude_deg.push_back(round_to_hundredths(alt));
    b.azimuth_deg.push_back(round_to_hundredths(az));
    b.pixel_shift_by_row.push_back(static_cast<int>(
        std::lround(b.azimuth_deg.back() * static_cast<double>(kColumnsPerFrame) / 360.0)));
  }
  return b;
}

template <class T>
void put(std::byte* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}

// Little-endian bytes [0, n) of v.
void put_bytes(std::byte* p, std::uint64_t v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<std::byte>((v >> (8 * i)) & 0xFFU);
}

// --- metadata JSON -------------------------------------------------------------------------

// Shortest text that parses back to exactly `v` (std::to_chars), so the decoder reads the very
// doubles the simulator used.
std::string json_number(double v) {
  std::array<char, 32> buf{};
  const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  return std::string(buf.data(), r.ptr);
}

template <class Range>
std::string json_array(const Range& values) {
  std::string s = "[";
  bool first = true;
  for (const auto& v : values) {
    if (!first) s += ", ";
    first = false;
    if constexpr (std::is_floating_point_v<std::decay_t<decltype(v)>>) {
      s += json_number(v);
    } else {
      s += std::to_string(v);
    }
  }
  return s + "]";
}

std::string json_string(std::string_view s) {
  return "\"" + std::string(s) + "\"";
}

std::string ipv4_text(std::uint32_t ip) {
  return std::to_string((ip >> 24) & 0xFFU) + "." + std::to_string((ip >> 16) & 0xFFU) + "." +
         std::to_string((ip >> 8) & 0xFFU) + "." + std::to_string(ip & 0xFFU);
}

// One JSON object member per line, members in the order given.
class JsonObject {
 public:
  explicit JsonObject(int indent) : indent_(indent) {}
  JsonObject& raw(std::string_view key, const std::string& value) {
    members_.push_back(std::string(static_cast<std::size_t>(indent_ + 2), ' ') + json_string(key) +
                       ": " + value);
    return *this;
  }
  JsonObject& str(std::string_view key, std::string_view value) {
    return raw(key, json_string(value));
  }
  JsonObject& num(std::string_view key, std::int64_t value) {
    return raw(key, std::to_string(value));
  }
  [[nodiscard]] std::string text() const {
    std::string s = "{\n";
    for (std::size_t i = 0; i < members_.size(); ++i) {
      s += members_[i] + (i + 1 < members_.size() ? ",\n" : "\n");
    }
    return s + std::string(static_cast<std::size_t>(indent_), ' ') + "}";
  }

 private:
  int indent_;
  std::vector<std::string> members_;
};

// Firmware 2.5 nested layout (the shape of GET /api/v1/sensor/metadata; template: ouster-sdk
// tests/metadata/2_5_0_os-992146000760-128.json).
std::string metadata_json(const Product& product, const BeamCalibration& beams,
                          std::uint32_t init_id, std::uint32_t host_ip,
                          std::uint32_t frames_per_second) {
  const std::string profile_lidar = "RNG19_RFL8_SIG16_NIR16";
  const std::string profile_imu = "LEGACY";
  const std::string lidar_mode =
      std::to_string(kColumnsPerFrame) + "x" + std::to_string(frames_per_second);
  const std::array<double, 16> beam_to_lidar{1, 0, 0, kBeamOriginMm, 0, 1, 0, 0, 0, 0, 1, 0, 0,
                                             0, 0, 1};
  const std::array<double, 16> lidar_to_sensor{
      -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, kLidarAboveSensorMm, 0, 0, 0, 1};
  const std::array<double, 16> imu_to_sensor{1, 0, 0, kImuInSensorMm[0], 0, 1, 0, kImuInSensorMm[1],
                                             0, 0, 1, kImuInSensorMm[2], 0, 0, 0, 1};

  JsonObject beam(2);
  beam.raw("beam_altitude_angles", json_array(beams.altitude_deg))
      .raw("beam_azimuth_angles", json_array(beams.azimuth_deg))
      .raw("beam_to_lidar_transform", json_array(beam_to_lidar))
      .raw("lidar_origin_to_beam_origin_mm", json_number(kBeamOriginMm));

  JsonObject reflectivity(4);
  reflectivity.str("timestamp", "2023-06-01T12:00:00").raw("valid", "true");
  JsonObject calibration(2);
  calibration.raw("reflectivity", reflectivity.text());

  JsonObject config(2);
  config.raw("azimuth_window", "[0, 360000]")
      .num("columns_per_packet", kColumnsPerPacket)
      .str("lidar_mode", lidar_mode)
      .str("multipurpose_io_mode", "OFF")
      .str("nmea_baud_rate", "BAUD_9600")
      .num("nmea_ignore_valid_char", 0)
      .str("nmea_in_polarity", "ACTIVE_HIGH")
      .num("nmea_leap_seconds", 0)
      .str("operating_mode", "NORMAL")
      .raw("phase_lock_enable", "false")
      .num("phase_lock_offset", 0)
      .num("signal_multiplier", 1)
      .str("sync_pulse_in_polarity", "ACTIVE_HIGH")
      .num("sync_pulse_out_angle", 360)
      .num("sync_pulse_out_frequency", 1)
      .str("sync_pulse_out_polarity", "ACTIVE_HIGH")
      .num("sync_pulse_out_pulse_width", 10)
      .str("timestamp_mode", "TIME_FROM_INTERNAL_OSC")
      .str("udp_dest", ipv4_text(host_ip))
      .num("udp_port_imu", kImuPort)
      .num("udp_port_lidar", kLidarPort)
      .str("udp_profile_imu", profile_imu)
      .str("udp_profile_lidar", profile_lidar);

  JsonObject imu(2);
  imu.raw("imu_to_sensor_transform", json_array(imu_to_sensor));

  JsonObject format(2);
  format.raw("column_window", "[0, " + std::to_string(kColumnsPerFrame - 1) + "]")
      .num("columns_per_frame", kColumnsPerFrame)
      .num("columns_per_packet", kColumnsPerPacket)
      .raw("pixel_shift_by_row", json_array(beams.pixel_shift_by_row))
      .num("pixels_per_column", product.rows)
      .str("udp_profile_imu", profile_imu)
      .str("udp_profile_lidar", profile_lidar);

  JsonObject lidar(2);
  lidar.raw("lidar_to_sensor_transform", json_array(lidar_to_sensor));

  JsonObject info(2);
  info.str("build_date", "2023-07-14T19:54:10Z")
      .str("build_rev", "v2.5.2")
      .str("image_rev", "ousteros-image-prod-aries-v2.5.2+20230714195410")
      .num("initialization_id", init_id)
      .str("prod_line", product.prod_line)
      .str("prod_pn", product.prod_pn)
      .str("prod_sn", product.prod_sn)
      .str("status", "RUNNING");

  JsonObject root(0);
  root.raw("beam_intrinsics", beam.text())
      .raw("calibration_status", calibration.text())
      .str("client_version", "livod sim")
      .raw("config_params", config.text())
      .raw("imu_intrinsics", imu.text())
      .raw("lidar_data_format", format.text())
      .raw("lidar_intrinsics", lidar.text())
      .raw("sensor_info", info.text());
  return root.text() + "\n";
}

// --- the sensor ------------------------------------------------------------------------------

class SimOuster final : public SimLidar {
 public:
  SimOuster(const Product& product, const SimLidarOptions& options)
      : product_(product),
        options_(options),
        beams_(os1_beams(product.rows)),
        lidar_clock_(options.clock, options.seed ^ 0x1111),
        imu_clock_(options.clock, options.seed ^ 0x4444),
        lidar_link_(options.link, options.seed ^ 0x2222),
        imu_link_(options.link, options.seed ^ 0x5555),
        imu_(options.imu_noise, options.seed ^ 0x3333),
        rng_(options.seed),
        // Constant for the sensor's power-on; 24 bits, never 0.
        init_id_(
            static_cast<std::uint32_t>(((options.seed * 0x9E3779B97F4A7C15ULL) >> 40) % 0xFFFFFFU) +
            1U),
        prod_sn_(std::stoull(product.prod_sn)),
        // Lidar modes 1024x10 and 1024x20 (scan_rate_hz picks one).
        frames_per_second_(options.scan_rate_hz >= 15.0 ? 20U : 10U) {
    build_geometry();
    packet_bytes_ = kPacketHeaderBytes +
                    kColumnsPerPacket * (kColumnHeaderBytes + product_.rows * kChannelBlockBytes) +
                    kPacketFooterBytes;
    T_sensor_imu_.translation() =
        1e-3 * Eigen::Vector3d(kImuInSensorMm[0], kImuInSensorMm[1], kImuInSensorMm[2]);
  }

  // The decoder registry has one entry for every Ouster: the metadata says which one.
  [[nodiscard]] std::string model() const override { return "OS"; }

  void run(double t_begin, double t_end, const SceneContext& scene, SimOutputs& out) override {
    // Sensor-clock periods in scenario time: the oscillator runs skew_ppm fast.
    const double rate = 1.0 + options_.clock.skew_ppm * 1e-6;
    const double column_s = 1.0 / (kColumnsPerFrame * frames_per_second_) / rate;
    // A packet belongs to the run() call whose interval holds its send time, the instant of its
    // last column: a D-second capture holds what the sensor sent in D seconds. With D a multiple
    // of 0.1 s that is whole frames as long as the clock runs fast by less than a packet
    // (1.46 ms) over D, e.g. the scenarios' +30 ppm up to 48 s.
    constexpr double kLastColumn = kColumnsPerPacket - 1;
    auto k = static_cast<std::int64_t>(
        std::ceil((t_begin / column_s - kLastColumn) / kColumnsPerPacket - 1e-9));
    for (k = std::max<std::int64_t>(k, 0);; ++k) {
      const auto first_column = static_cast<std::uint64_t>(k) * kColumnsPerPacket;
      if ((static_cast<double>(first_column) + kLastColumn) * column_s >= t_end) break;
      emit_lidar_packet(first_column, column_s, scene, out);
    }
    if (options_.imu) {
      const double period = 1.0 / options_.imu_noise.rate_hz;
      const double gyro_after_sys = static_cast<double>(kImuGyroAfterSysNs) * 1e-9;
      auto j =
          static_cast<std::int64_t>(std::ceil((t_begin * rate - gyro_after_sys) / period - 1e-9));
      for (j = std::max<std::int64_t>(j, 0);; ++j) {
        const double t = (static_cast<double>(j) * period + gyro_after_sys) / rate;
        if (t >= t_end) break;
        emit_imu(t, scene, out);
      }
    }
  }

  std::vector<std::filesystem::path> write_side_files(const std::filesystem::path& dir,
                                                      const std::string& stem) const override {
    const std::filesystem::path path = dir / (stem + ".json");
    std::ofstream os(path, std::ios::binary);
    os << metadata_json(product_, beams_, init_id_, options_.host_ip, frames_per_second_);
    os.flush();
    if (!os) throw Error("cannot write Ouster metadata " + path.string());
    return {path};
  }

 private:
  // One measurement column's fixed geometry (sensor frame): the §3.6 model with
  // theta_e = 2 pi (1 - v / W) is p = origin + 1e-3 (r - n) R b_u for wire range r (mm).
  struct Column {
    Eigen::Matrix3d R_sensor_beam;  // R_sensor_lidar Rz(theta_e)
    Eigen::Vector3d origin_m;       // beam origin of every row of this column
  };

  void build_geometry() {
    constexpr double kDeg = std::numbers::pi / 180.0;
    for (std::uint32_t u = 0; u < product_.rows; ++u) {
      const double theta_a = -beams_.azimuth_deg[u] * kDeg;
      const double phi = beams_.altitude_deg[u] * kDeg;
      beam_dirs_.emplace_back(std::cos(theta_a) * std::cos(phi), std::sin(theta_a) * std::cos(phi),
                              std::sin(phi));
    }
    Eigen::Matrix3d R_sensor_lidar = Eigen::Matrix3d::Identity();
    R_sensor_lidar(0, 0) = -1.0;
    R_sensor_lidar(1, 1) = -1.0;
    const Eigen::Vector3d t_sensor_lidar_mm(0.0, 0.0, kLidarAboveSensorMm);
    // beam_to_lidar has no vertical offset, so n = |(B03, B23)| = B03.
    beam_offset_m_ = kBeamOriginMm * 1e-3;
    columns_.reserve(kColumnsPerFrame);
    for (std::uint32_t v = 0; v < kColumnsPerFrame; ++v) {
      const double theta_e =
          2.0 * std::numbers::pi * (1.0 - static_cast<double>(v) / kColumnsPerFrame);
      const Eigen::Matrix3d Rz =
          Eigen::AngleAxisd(theta_e, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      Column c;
      c.R_sensor_beam = R_sensor_lidar * Rz;
      c.origin_m = 1e-3 * (R_sensor_lidar * (Rz * Eigen::Vector3d(kBeamOriginMm, 0.0, 0.0)) +
                           t_sensor_lidar_mm);
      columns_.push_back(c);
    }
  }

  void emit_lidar_packet(std::uint64_t first_column, double column_s, const SceneContext& scene,
                         SimOutputs& out) {
    std::vector<std::byte> payload(packet_bytes_);
    std::byte* p = payload.data();
    const std::uint64_t frame = first_column / kColumnsPerFrame;
    put<std::uint16_t>(p, kLidarPacketType);
    put<std::uint16_t>(p + 2, static_cast<std::uint16_t>((kFirstFrameId + frame) & 0xFFFFU));
    put_bytes(p + 4, init_id_, 3);
    put_bytes(p + 7, prod_sn_, 5);
    // Alert flags, thermal and shot-limiting states stay 0: a healthy sensor.

    const std::size_t column_bytes = kColumnHeaderBytes + product_.rows * kChannelBlockBytes;
    double t = 0.0;
    for (std::uint32_t c = 0; c < kColumnsPerPacket; ++c) {
      const std::uint64_t n = first_column + c;
      const auto v = static_cast<std::uint32_t>(n % kColumnsPerFrame);
      t = static_cast<double>(n) * column_s;
      std::byte* col = p + kPacketHeaderBytes + c * column_bytes;
      put<std::uint64_t>(col, static_cast<std::uint64_t>(lidar_clock_.stamp_ns(t)));
      put<std::uint16_t>(col + 8, static_cast<std::uint16_t>(v));
      put<std::uint16_t>(col + 10, kColumnStatusValid);
      cast_column(t, columns_[v], col + kColumnHeaderBytes, scene, out);
    }
    const std::size_t body = payload.size() - kCrcBytes;
    put<std::uint64_t>(p + body, drivers::ouster::crc64_xz(std::span(payload).first(body)));
    // The packet leaves once its last column is measured.
    send(t, kLidarPort, std::move(payload), lidar_link_, out);
  }

  // Ray-casts every row of one column (all measured at time t, one pose) and writes the channel
  // blocks.
  void cast_column(double t, const Column& column, std::byte* blocks, const SceneContext& scene,
                   SimOutputs& out) {
    const RangeModel& range = options_.range;
    const Eigen::Isometry3d T_world_sensor = scene.T_world_sensor(t);
    const Eigen::Matrix3d R_world_beam = T_world_sensor.linear() * column.R_sensor_beam;
    const Eigen::Vector3d origin_world = T_world_sensor * column.origin_m;
    const Eigen::Vector3d up_world = T_world_sensor.linear().col(2);
    SimPointTruth truth;
    truth.t = t;
    for (std::uint32_t u = 0; u < product_.rows; ++u) {
      std::byte* block = blocks + u * kChannelBlockBytes;
      const Eigen::Vector3d dir_world = R_world_beam * beam_dirs_[u];
      std::uint32_t range_mm = 0;
      const LidarReturn ret =
          measure_return(scene, t, origin_world, dir_world, up_world, range, rng_);
      const double surface_reflectivity = ret.reflectivity;
      const double incidence_cos = ret.incidence_cos;
      const double distance_m = ret.range_m;
      if (ret.valid) {
        // The wire range counts from the lidar axis: the beam origin is n = 15.806 mm out.
        const auto mm = std::llround((distance_m + beam_offset_m_) * 1000.0);
        if (mm > 0 && mm <= kMaxWireRangeMm) range_mm = static_cast<std::uint32_t>(mm);
      }
      write_channel(block, range_mm, surface_reflectivity, incidence_cos, distance_m);
      truth.ring = static_cast<std::uint16_t>(u);
      truth.valid = range_mm != 0;
      if (truth.valid) {
        truth.p_sensor = column.origin_m + (static_cast<double>(range_mm) * 1e-3 - beam_offset_m_) *
                                               (column.R_sensor_beam * beam_dirs_[u]);
        truth.reflectivity = static_cast<float>(std::to_integer<std::uint8_t>(block[4]));
      } else {
        truth.p_sensor.setZero();
        truth.reflectivity = 0.0F;
      }
      if (out.on_point) out.on_point(truth);
    }
  }

  // RANGE bits 0-18 (FLAGS 19-23 zero), REFLECTIVITY byte 4, SIGNAL bytes 6-7, NEAR_IR bytes 8-9.
  void write_channel(std::byte* block, std::uint32_t range_mm, double surface_reflectivity,
                     double incidence_cos, double distance_m) const {
    put<std::uint32_t>(block, range_mm);
    // Ambient near-infrared light reflected by whatever the pixel looks at (dark when nothing).
    const double near_ir = 8.0 + 600.0 * surface_reflectivity * (0.5 + 0.5 * incidence_cos);
    put<std::uint16_t>(block + 8, static_cast<std::uint16_t>(std::lround(near_ir)));
    if (range_mm == 0) return;
    const double reflectivity =
        std::clamp(surface_reflectivity * options_.range.reflectivity_gain, 0.0, 255.0);
    block[4] = static_cast<std::byte>(static_cast<std::uint8_t>(std::lround(reflectivity)));
    // Returned photons: Lambertian target, inverse-square falloff (about 2000 at 1 m for a 50 %
    // target head-on, single digits at 20 m).
    const double d = std::max(distance_m, 0.3);
    const double signal = 4000.0 * surface_reflectivity * incidence_cos / (d * d);
    put<std::uint16_t>(block + 6,
                       static_cast<std::uint16_t>(std::clamp(std::lround(signal), 1L, 65535L)));
  }

  void emit_imu(double t, const SceneContext& scene, SimOutputs& out) {
    const Eigen::Isometry3d T_body_imu = scene.T_body_sensor * T_sensor_imu_;
    const ImuTruth m = imu_.measure(scene.imu_truth(t, T_body_imu));
    if (out.on_imu) out.on_imu(SimImuTruth{t, m.gyro_rad_s, m.accel_m_s2});
    const std::int64_t gyro_ts = imu_clock_.stamp_ns(t);
    const auto before = [gyro_ts](std::int64_t ns) {
      return static_cast<std::uint64_t>(std::max<std::int64_t>(gyro_ts - ns, 0));
    };
    std::vector<std::byte> payload(kLegacyImuPacketBytes);
    std::byte* p = payload.data();
    put<std::uint64_t>(p, before(kImuGyroAfterSysNs));
    put<std::uint64_t>(p + 8, before(kImuGyroAfterSysNs - kImuAccelAfterSysNs));
    put<std::uint64_t>(p + 16, static_cast<std::uint64_t>(gyro_ts));
    for (int i = 0; i < 3; ++i) {
      put<float>(p + 24 + 4 * i, static_cast<float>(m.accel_m_s2[i] / kStandardGravity));
      put<float>(p + 36 + 4 * i, static_cast<float>(m.gyro_rad_s[i] * kDegreesPerRadian));
    }
    send(t, kImuPort, std::move(payload), imu_link_, out);
  }

  void send(double t_sent, std::uint16_t port, std::vector<std::byte>&& payload, Link& link,
            SimOutputs& out) const {
    const double delay = link.delay_s();
    if (delay < 0.0) return;  // lost
    SimDatagram d;
    d.host_time_ns =
        static_cast<std::int64_t>(std::llround((options_.host_epoch_s + t_sent + delay) * 1e9));
    d.src_ip = options_.sensor_ip;
    d.src_port = port;  // the sensor sends from the port it sends to
    d.dst_port = port;
    d.payload = std::move(payload);
    out.on_datagram(std::move(d));
  }

  Product product_;
  SimLidarOptions options_;
  BeamCalibration beams_;
  // The lidar and the IMU stamp on one clock; separate objects (same faults, separate jitter
  // draws) and separate links keep the output independent of how run() is chunked.
  SensorClock lidar_clock_;
  SensorClock imu_clock_;
  Link lidar_link_;
  Link imu_link_;
  ImuModel imu_;
  std::mt19937_64 rng_;
  std::uint32_t init_id_;
  std::uint64_t prod_sn_;
  std::uint32_t frames_per_second_;
  std::size_t packet_bytes_ = 0;
  std::vector<Eigen::Vector3d> beam_dirs_;  // b_u per row (lidar frame, unit)
  std::vector<Column> columns_;
  double beam_offset_m_ = 0.0;
  Eigen::Isometry3d T_sensor_imu_ = Eigen::Isometry3d::Identity();
};

}  // namespace

std::unique_ptr<SimLidar> make_sim_os1_64(const SimLidarOptions& options) {
  return std::make_unique<SimOuster>(kOs1_64, options);
}

std::unique_ptr<SimLidar> make_sim_os1_128(const SimLidarOptions& options) {
  return std::make_unique<SimOuster>(kOs1_128, options);
}

}  // namespace livod::sim
