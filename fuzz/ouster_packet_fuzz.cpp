// libFuzzer target: Ouster packet decoding and scan assembly on arbitrary bytes.
//
// Input: byte 0 selects one of several sensor configurations (LEGACY, single, dual, low data
// rate, FUSA and zone profiles; 16-128 beams; LEGACY and ACCEL32_GYRO32_NMEA IMU; with and
// without CRC; plain and wrapping column windows); the rest is one UDP payload. The payload goes
// through the pure decoders (every field of every pixel is read, so ASan checks each access) and
// through a long-lived OusterDecoder per configuration, whose frame-tracking state therefore
// carries over between inputs.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <span>

#include "drivers/ouster/imu_packet.hpp"
#include "drivers/ouster/lidar_packet.hpp"
#include "drivers/ouster/ouster_decoder.hpp"

namespace {

using livod::drivers::ouster::ChannelField;
using livod::drivers::ouster::HeaderType;
using livod::drivers::ouster::ImuProfile;
using livod::drivers::ouster::LidarProfile;
using livod::drivers::ouster::SensorMetadata;

struct Config {
  LidarProfile profile;
  std::uint32_t rows;
  std::uint32_t columns_per_frame;
  std::uint32_t window_first;
  std::uint32_t window_last;
  ImuProfile imu;
  std::uint32_t imu_per_packet;  // 0: inferred from the size
  bool crc;                      // firmware 3.x (CRC footers) or 2.3 (none)
};

constexpr std::array<Config, 9> kConfigs{{
    {LidarProfile::kLegacy, 16, 512, 0, 511, ImuProfile::kLegacy, 0, false},
    {LidarProfile::kLegacy, 64, 1024, 912, 1022, ImuProfile::kLegacy, 0, false},
    {LidarProfile::kRng19Rfl8Sig16Nir16, 128, 1024, 0, 1023, ImuProfile::kLegacy, 0, false},
    {LidarProfile::kRng19Rfl8Sig16Nir16Dual, 32, 1024, 370, 85, ImuProfile::kLegacy, 0, false},
    {LidarProfile::kRng15Rfl8Nir8, 128, 512, 1, 256, ImuProfile::kLegacy, 0, true},
    {LidarProfile::kRng15Rfl8Nir8Dual, 64, 2048, 0, 2047, ImuProfile::kAccel32Gyro32Nmea, 8, false},
    {LidarProfile::kFusaRng15Rfl8Nir8Dual, 128, 1024, 0, 1023, ImuProfile::kLegacy, 0, false},
    {LidarProfile::kRng19Rfl8Sig16Nir16Zone16, 32, 512, 0, 511, ImuProfile::kAccel32Gyro32Nmea, 0,
     false},
    {LidarProfile::kRng15Rfl8Nir8Zone16, 16, 1024, 0, 1023, ImuProfile::kAccel32Gyro32Nmea, 8,
     true},
}};

SensorMetadata make_metadata(const Config& c) {
  SensorMetadata m;
  m.prod_line = "OS-1-128";
  m.prod_sn = "122246000293";
  m.prod_sn_number = 122246000293ULL;
  m.initialization_id = 390076;
  m.firmware = c.crc ? livod::drivers::ouster::FirmwareVersion{3, 2, 0}
                     : livod::drivers::ouster::FirmwareVersion{2, 3, 0};
  m.lidar_origin_to_beam_origin_mm = 15.806;
  m.T_lidar_beam_mm(0, 3) = 15.806;
  m.T_sensor_lidar_mm(0, 0) = -1;
  m.T_sensor_lidar_mm(1, 1) = -1;
  m.T_sensor_lidar_mm(2, 3) = 36.18;
  for (std::uint32_t u = 0; u < c.rows; ++u) {
    m.beam_altitude_angles_deg.push_back(20.0 - 40.0 * u / c.rows);
    m.beam_azimuth_angles_deg.push_back(u % 4 == 0 ? 3.0 : -1.0);
  }
  auto& f = m.format;
  f.pixels_per_column = c.rows;
  f.columns_per_packet = 16;
  f.columns_per_frame = c.columns_per_frame;
  f.pixel_shift_by_row.assign(c.rows, 0);
  f.column_window = {c.window_first, c.window_last};
  f.udp_profile_lidar = c.profile;
  f.udp_profile_imu = c.imu;
  f.header_type =
      c.profile == LidarProfile::kFusaRng15Rfl8Nir8Dual ? HeaderType::kFusa : HeaderType::kStandard;
  f.imu_measurements_per_packet = c.imu_per_packet;
  return m;
}

constexpr std::array<ChannelField, livod::drivers::ouster::kChannelFieldCount> kFields{
    ChannelField::kRange,      ChannelField::kRange2,       ChannelField::kFlags,
    ChannelField::kFlags2,     ChannelField::kReflectivity, ChannelField::kReflectivity2,
    ChannelField::kSignal,     ChannelField::kSignal2,      ChannelField::kNearIr,
    ChannelField::kWindow,     ChannelField::kZoneMask,     ChannelField::kRaw32Word1,
    ChannelField::kRaw32Word2, ChannelField::kRaw32Word3,   ChannelField::kRaw32Word4};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace livod::drivers::ouster;  // NOLINT: local to the fuzz entry point
  if (size < 1) return 0;
  // One decoder per configuration, alive for the whole run (state carries across inputs).
  static std::array<std::unique_ptr<OusterDecoder>, kConfigs.size()> decoders;
  const std::size_t which = data[0] % kConfigs.size();
  if (!decoders[which]) {
    decoders[which] = std::make_unique<OusterDecoder>(make_metadata(kConfigs[which]));
  }
  OusterDecoder& decoder = *decoders[which];
  const PacketFormat& format = decoder.packet_format();
  const std::span<const std::byte> payload(reinterpret_cast<const std::byte*>(data + 1), size - 1);

  unsigned sink = 0;
  LidarPacket lidar;
  if (LidarPacket::parse(payload, format, lidar) == PacketError::kNone) {
    for (std::uint32_t c = 0; c < lidar.columns(); ++c) {
      sink += static_cast<unsigned>(lidar.column_timestamp_ns(c)) + lidar.measurement_id(c) +
              lidar.column_status(c) + lidar.column_frame_id(c) + lidar.column_encoder_count(c);
      if (lidar.measurement_id(c) >= format.columns_per_frame) std::abort();
      for (std::uint32_t px = 0; px < format.pixels_per_column; ++px) {
        for (ChannelField f : kFields) sink += lidar.field(c, px, f);
      }
    }
  }
  ImuPacket imu;
  if (parse_imu_packet(payload, format, imu) == PacketError::kNone) {
    if (imu.count == 0 || imu.count > imu.measurements.size()) std::abort();
    sink += static_cast<unsigned>(imu.nmea_sentence.size());
  }
  PacketHeader header;
  static_cast<void>(check_zone_packet(payload, format, header));

  livod::drivers::DecoderSinks sinks;
  sinks.on_scan = [&sink](const livod::LidarScan& s) {
    if (s.x.size() != s.t_offset_ns.size() || s.x.size() != s.valid.size()) std::abort();
    for (std::size_t i = 0; i < s.size(); ++i) sink += static_cast<unsigned>(s.ring[i]);
  };
  sinks.on_imu = [&sink](const livod::ImuSample& s) {
    sink += static_cast<unsigned>(s.stamp.sensor.ns);
  };
  const auto before = decoder.counters().packets;
  decoder.on_packet({payload, 0, 7502}, sinks);
  if (decoder.counters().packets != before + 1) std::abort();
  if (data[0] >= 0xF0) decoder.flush(sinks);
  static_cast<void>(sink);
  return 0;
}
