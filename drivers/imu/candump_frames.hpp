#pragma once
// Conversions between candump log frames (io/candump.hpp) and the decoders' CanRecord, so that a
// logged frame reaches a CAN IMU decoder exactly as the live socket would deliver it.

#include <string>

#include "drivers/imu/imu_decoder.hpp"
#include "io/candump.hpp"

namespace livod::imu {

// The log time becomes the receive time.
[[nodiscard]] CanRecord to_can_record(const io::CanFrame& frame);
// `interface` names the bus in the log line ("can0").
[[nodiscard]] io::CanFrame to_candump_frame(const CanRecord& record, const std::string& interface);

}  // namespace livod::imu
