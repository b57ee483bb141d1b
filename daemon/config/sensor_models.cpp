#include "daemon/config/sensor_models.hpp"

#include <algorithm>
#include <cctype>

namespace livod::daemon {

namespace {

std::string upper(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace

std::vector<std::string> known_models(Driver driver) {
  switch (driver) {
    case Driver::ouster: {
      std::vector<std::string> models;
      for (const char* family : {"OS0", "OS1", "OS2"}) {
        for (const char* beams : {"16", "32", "64", "128"}) {
          models.push_back(std::string(family) + "-" + beams);
        }
      }
      return models;
    }
    case Driver::velodyne:
      return {"VLP-16", "VLP-32C", "HDL-32E", "VLS-128"};
    case Driver::livox_sdk1:
      return {"AVIA", "HORIZON", "MID-40", "MID-70", "TELE-15"};
    case Driver::livox_sdk2:
      return {"MID-360", "HAP"};
    default:
      return {};
  }
}

bool model_required(Driver driver) {
  // Ouster reads its model from the metadata; a configured model is only cross-checked.
  return driver == Driver::velodyne || driver == Driver::livox_sdk1 || driver == Driver::livox_sdk2;
}

std::optional<std::string> canonical_model(Driver driver, std::string_view model) {
  const auto models = known_models(driver);
  if (models.empty()) return std::string(model);
  std::string wanted = upper(model);
  // Ouster's own metadata spells the product line "OS-1-128".
  if (driver == Driver::ouster && wanted.rfind("OS-", 0) == 0) wanted.erase(2, 1);
  for (const auto& m : models) {
    if (m == wanted) return m;
  }
  return std::nullopt;
}

bool driver_has_internal_imu_models(Driver driver) {
  return driver == Driver::ouster || driver == Driver::livox_sdk1 || driver == Driver::livox_sdk2 ||
         driver == Driver::velodyne;
}

bool model_has_internal_imu(Driver driver, std::string_view canonical) {
  switch (driver) {
    case Driver::ouster:
    case Driver::livox_sdk2:
      return true;
    case Driver::livox_sdk1:
      // Mid-40 and Mid-70 have no IMU (the IMU push-rate command is not available on them).
      return canonical != "MID-40" && canonical != "MID-70";
    case Driver::velodyne:
      // Of the Velodynes only the HDL-32E sends gyro and accelerometer words (position packets).
      return canonical == "HDL-32E";
    default:
      return false;
  }
}

UdpPorts default_ports(Driver driver, std::string_view canonical) {
  UdpPorts ports;
  switch (driver) {
    case Driver::ouster:
      ports.lidar = 7502;
      ports.imu = 7503;
      break;
    case Driver::velodyne:
      ports.lidar = 2368;
      ports.position = 8308;
      break;
    case Driver::livox_sdk1:
      // Livox-SDK's choice for the first device: data and IMU share one port.
      ports.lidar = 56001;
      ports.imu = 56001;
      ports.command = 55501;
      break;
    case Driver::livox_sdk2:
      if (canonical == "HAP") {
        ports.command = 56000;
        ports.lidar = 57000;
        ports.imu = 58000;
      } else {
        ports.command = 56101;
        ports.push = 56201;
        ports.lidar = 56301;
        ports.imu = 56401;
      }
      break;
    default:
      break;
  }
  return ports;
}

std::vector<std::string> port_names(Driver driver) {
  switch (driver) {
    case Driver::ouster:
      return {"lidar", "imu"};
    case Driver::velodyne:
      return {"lidar", "position"};
    case Driver::livox_sdk1:
      return {"lidar", "imu", "command"};
    case Driver::livox_sdk2:
      return {"lidar", "imu", "command", "push"};
    default:
      return {};
  }
}

FrameCutMode default_frame_cut(Driver driver) {
  switch (driver) {
    case Driver::ouster:
      return FrameCutMode::frame_id;
    case Driver::velodyne:
      return FrameCutMode::azimuth;
    default:
      return FrameCutMode::time;
  }
}

std::vector<FrameCutMode> allowed_frame_cuts(Driver driver) {
  switch (driver) {
    case Driver::ouster:
      // The Ouster decoder cuts at the sensor's own frame boundaries only; an azimuth or time cut
      // would be accepted here and refused by the run.
      return {FrameCutMode::frame_id};
    case Driver::velodyne:
      return {FrameCutMode::azimuth, FrameCutMode::time};
    case Driver::livox_sdk1:
    case Driver::livox_sdk2:
      // Non-repetitive scan patterns have no azimuth wrap and no frame counter.
      return {FrameCutMode::time};
    default:
      return {};
  }
}

std::vector<ReplayFormat> replay_formats(Driver driver) {
  switch (driver) {
    case Driver::ouster:
    case Driver::velodyne:
    case Driver::livox_sdk1:
    case Driver::livox_sdk2:
      return {ReplayFormat::pcap, ReplayFormat::rosbag1};
    case Driver::v4l2:
    case Driver::aravis:
    case Driver::dataset_camera:
    case Driver::dataset_imu:
      return {ReplayFormat::euroc, ReplayFormat::rosbag1};
    case Driver::can_imu:
      return {ReplayFormat::candump, ReplayFormat::rosbag1};
    case Driver::dataset_lidar:
      return {ReplayFormat::rosbag1};
    case Driver::serial_imu:
      return {};
  }
  return {};
}

bool supports_udp(Driver driver) {
  return is_packet_lidar(driver);
}

bool supports_device(Driver driver) {
  return driver == Driver::v4l2 || driver == Driver::aravis || driver == Driver::can_imu ||
         driver == Driver::serial_imu;
}

int default_ring_capacity(SensorKind kind) {
  switch (kind) {
    case SensorKind::lidar:
      return 1024;  // packets: 0.5 s of a Mid-360, 1.6 s of an OS1-128 at 1024x10
    case SensorKind::imu:
      return 1024;  // samples: 5 s at 200 Hz
    case SensorKind::camera:
      return 8;  // frames: images are large; a late scheduler drops frames, not memory
  }
  return 1024;
}

}  // namespace livod::daemon
