#include "drivers/ouster/ouster_family.hpp"

#include "drivers/ouster/ouster_factory.hpp"

namespace livod::drivers::ouster {
namespace {

constexpr UdpPorts kPorts{.lidar = 7502, .imu = 7503};  // sensor-protocols.md 3.1
// The metadata spells the product line "OS-1-64"; normalised, that is this table's "OS1-64".
constexpr double kColumnsPerSecond = 1024.0 * 10.0;  // the factory mode, 1024x10

// Points per second in the factory mode (1024 x 10 Hz) x beams. Maximum ranges: Ouster's
// datasheets (OS0 50 m, OS1 120 m, OS2 240 m at high reflectivity); range error and beam
// divergence differ by hardware revision and are not in livod's sources.
constexpr LidarModelInfo model(std::string_view name, std::string_view summary, int beams,
                               double max_range_m) {
  return {name, {},    summary,     beams,        beams * kColumnsPerSecond,
          10.0, 0.0,   max_range_m, std::nullopt, std::nullopt,
          true, kPorts};
}

constexpr std::array<LidarModelInfo, 13> kModels{{
    {"OS",
     {},
     "Ouster OS0/OS1/OS2, any beam count (the metadata tells)",
     0,
     0.0,
     10.0,
     0.0,
     0.0,
     std::nullopt,
     std::nullopt,
     true,
     kPorts},
    model("OS0-16", "Ouster OS0-16", 16, 50.0),
    model("OS0-32", "Ouster OS0-32", 32, 50.0),
    model("OS0-64", "Ouster OS0-64", 64, 50.0),
    model("OS0-128", "Ouster OS0-128", 128, 50.0),
    model("OS1-16", "Ouster OS1-16", 16, 120.0),
    model("OS1-32", "Ouster OS1-32", 32, 120.0),
    model("OS1-64", "Ouster OS1-64", 64, 120.0),
    model("OS1-128", "Ouster OS1-128", 128, 120.0),
    model("OS2-16", "Ouster OS2-16", 16, 240.0),
    model("OS2-32", "Ouster OS2-32", 32, 240.0),
    model("OS2-64", "Ouster OS2-64", 64, 240.0),
    model("OS2-128", "Ouster OS2-128", 128, 240.0),
}};
constexpr std::array<std::string_view, 2> kPortNames{"lidar", "imu"};
// Frames are the sensor's own (frame_id); other cuts are not implemented.
constexpr std::array<CutMode, 1> kCuts{CutMode::kFrameId};

std::unique_ptr<LidarDecoder> make(const LidarDecoderConfig& config) {
  return make_ouster_decoder(config);
}

}  // namespace

const LidarFamily& ouster_family() {
  static const LidarFamily kFamily{
      .driver = "ouster",
      .vendor = "Ouster",
      .models = kModels,
      .model_required = false,  // the metadata names the product; a configured one is checked
      .port_names = kPortNames,
      .cut_modes = kCuts,
      .file = DecoderFile::kMetadata,
      // Before the metadata is known: the largest profile (128 beams, dual return, 16 columns)
      // is about 33 KB. IMU packets: 48 B (LEGACY) to ~2.5 KB (ACCEL32_GYRO32_NMEA).
      .lidar_datagram_bytes = 34 * 1024,
      .aux_datagram_bytes = 4096,
      .sensor_time_wrap_ns = 0,
      .read_settings = nullptr,
      .make_decoder = &make,
  };
  return kFamily;
}

}  // namespace livod::drivers::ouster
