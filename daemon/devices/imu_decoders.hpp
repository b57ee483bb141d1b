#pragma once
// The IMU decoder a sensor's configuration asks for, shared by replay (candump logs) and the live
// sources (device_sources.hpp), so that both decode identically.

#include <memory>
#include <string>

#include "daemon/config/config.hpp"
#include "drivers/imu/imu_decoder.hpp"

namespace livod::daemon::devices {

// can.decoder: sbg (with can.ids), bosch_mm7, custom (can.signals, can.sample_id). Throws
// livod::Error naming the sensor when the custom description is invalid (check-config reports the
// same problems earlier).
std::unique_ptr<imu::CanImuDecoder> make_can_imu_decoder(const CanConfig& can,
                                                         const std::string& sensor);

// serial.protocol: xsens_mtdata2. vectornav_binary is rejected (livod does not decode it).
std::unique_ptr<imu::StreamImuDecoder> make_serial_imu_decoder(const SerialConfig& serial,
                                                               const std::string& sensor);

}  // namespace livod::daemon::devices
