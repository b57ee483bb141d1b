#pragma once
// What the configuration needs to know about each driver: for the LiDARs decoded from packets
// this is their family's descriptor (drivers/lidar_family.hpp: models and aliases, ports, internal
// IMU, frame cuts, files, section); the camera, IMU and dataset drivers are described here.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/config/config.hpp"
#include "drivers/lidar_family.hpp"

namespace livod::daemon {

// The family of a driver that decodes LiDAR packets; nullptr for every other driver.
const drivers::LidarFamily* lidar_family(Driver driver);

// Canonical model names the driver accepts; empty = free text (cameras, IMUs, datasets).
std::vector<std::string> known_models(Driver driver);
bool model_required(Driver driver);
// The canonical spelling of `model` for this driver ("os-1-64" -> "OS1-64"), or nullopt.
std::optional<std::string> canonical_model(Driver driver, std::string_view model);

// Drivers with at least one model that has an internal IMU: their sensors take an `imu` section.
bool driver_has_internal_imu_models(Driver driver);
// Whether the model has an internal IMU (the family tables: Ouster all, Livox all but Mid-40 and
// Mid-70, the Velodyne HDL-32E in its position packets).
bool model_has_internal_imu(Driver driver, std::string_view canonical);
// Factory host ports of the first unit of this model.
UdpPorts default_ports(Driver driver, std::string_view canonical);
// The port names (keys of source.udp.ports) this driver receives on.
std::vector<std::string> port_names(Driver driver);

FrameCutMode default_frame_cut(Driver driver);
std::vector<FrameCutMode> allowed_frame_cuts(Driver driver);
drivers::CutMode to_cut_mode(FrameCutMode mode);

// What the family's decoder factory takes for this sensor (model, files, frame cut, section).
drivers::LidarDecoderConfig decoder_config(const SensorConfig& sensor);

std::vector<ReplayFormat> replay_formats(Driver driver);
bool supports_udp(Driver driver);
bool supports_device(Driver driver);

// Packets (LiDAR), samples (IMU) or frames (camera) buffered between capture and scheduler.
int default_ring_capacity(SensorKind kind);

}  // namespace livod::daemon
