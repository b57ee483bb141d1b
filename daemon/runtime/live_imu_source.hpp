#pragma once
// An external IMU live, as a runtime source: a SocketCAN IMU (SBG, Bosch MM7, custom decoder) or
// a serial / USB IMU (Xsens MTData2), whose capture thread (drivers/imu/imu_source.hpp, opened by
// daemon/devices/device_sources.hpp) fills a ring with CAN frames or serial reads. The scheduler
// drains it one frame / read per event, merged with the other sensors on the receive time; the
// decoder (the same object replay uses for candump logs and serial captures) turns them into
// samples that go through the sensor's clock domain (SensorClockMapper: free_running for SBG and
// Xsens, whose protocols carry a clock; receive_time for MM7 and custom CAN), then to the estimator
// when the IMU is the body IMU.
//
//   CAN bus / tty / USB --> capture thread --ring--> deliver(): decoder --> DecoderSinks::on_imu
//
// An IMU that cannot be opened at start is not fatal: it is logged (naming the sensor and the
// device), reported in health (WAITING then STALE, device OPENING, last_error) and retried every
// second, so a robot may boot before its USB IMU enumerates; a lost one (interface down, adapter
// unplugged) is STALE and reopened (docs/daemon.md).
//
// Recorded (`livod record`, outputs.record; docs/record.md): the capture thread copies each frame
// or read into the recorder's tap beside its ring to the scheduler; neither waits for the other.

#include <memory>

#include "daemon/config/config.hpp"
#include "daemon/runtime/source.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::daemon::record {
class Recorder;
}

namespace livod::daemon::runtime {

// Starts the IMU's capture thread (driver can_imu or serial_imu with a device source). Throws
// livod::Error naming the sensor only for what waiting cannot fix (an invalid custom CAN
// description, a protocol livod does not decode). `doorbell` (may be null) is rung on data.
// `recorder` (may be null; not started yet): the capture thread also copies every CAN frame /
// serial read into a tap of this recorder, which writes <sensor>.log / <sensor>.serial.
std::unique_ptr<MeasurementSource> open_live_imu(const SensorConfig& sensor,
                                                 const LivodConfig& config,
                                                 drivers::capture::Doorbell* doorbell,
                                                 record::Recorder* recorder = nullptr);

}  // namespace livod::daemon::runtime
