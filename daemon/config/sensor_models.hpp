#pragma once
// What the configuration needs to know about each driver and model: the model names it accepts,
// factory UDP ports, whether the model has an internal IMU, how its scans may be cut and which
// recorded formats carry its data. Facts from docs/sensor-protocols.md.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/config/config.hpp"

namespace livod::daemon {

// Canonical model names the driver accepts; empty = free text (cameras, IMUs, datasets).
std::vector<std::string> known_models(Driver driver);
bool model_required(Driver driver);
// The canonical spelling of `model` for this driver ("os-1-64" -> "OS1-64"), or nullopt.
std::optional<std::string> canonical_model(Driver driver, std::string_view model);

// Drivers with at least one model that has an internal IMU: their sensors take an `imu` section.
bool driver_has_internal_imu_models(Driver driver);
// The internal IMUs: Ouster (all), Livox SDK2 (all), Livox SDK1 except Mid-40/Mid-70, and the
// Velodyne HDL-32E (gyros and accelerometers in its position packets, on the position port).
bool model_has_internal_imu(Driver driver, std::string_view canonical);
// Factory host ports of the first unit of this model.
UdpPorts default_ports(Driver driver, std::string_view canonical);
// The port names (keys of source.udp.ports) this driver receives on.
std::vector<std::string> port_names(Driver driver);

FrameCutMode default_frame_cut(Driver driver);
std::vector<FrameCutMode> allowed_frame_cuts(Driver driver);

std::vector<ReplayFormat> replay_formats(Driver driver);
bool supports_udp(Driver driver);
bool supports_device(Driver driver);

// Packets (LiDAR), samples (IMU) or frames (camera) buffered between capture and scheduler.
int default_ring_capacity(SensorKind kind);

}  // namespace livod::daemon
