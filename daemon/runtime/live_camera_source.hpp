#pragma once
// A live camera (V4L2, or GigE/USB3 Vision through Aravis) as a runtime source: the camera's
// capture thread (drivers/camera/camera_source.hpp, opened by daemon/devices/device_sources.hpp)
// fills a frame ring; the scheduler drains it one frame per event, merged with the other sensors
// on the frame's host receive time, and hands each frame to the visual update like a replayed one.
//
//   camera --V4L2 / Aravis--> capture thread --FrameRing--> deliver(): CameraClock (the camera's
//   clock domain: mid-exposure on the host timeline, time_offset_s once) --> to_image_frame (the
//   one copy the estimator keeps) --> DecoderSinks::on_image
//
// The frames leave this source already mapped and decimated (delivers_mapped_images()): the
// camera clock knows the frame's clock kind (host monotonic, device ticks, PTP), its stamp instant
// and readout, which the scheduler's generic clock domain does not.
//
// A camera that cannot be opened at start is not fatal: it is logged (naming the sensor and the
// device), reported in health (state WAITING then STALE, device OPENING, last_error) and retried
// every second; a camera lost while streaming is STALE, closed and reopened (docs/daemon.md).

#include <memory>

#include "daemon/config/config.hpp"
#include "daemon/runtime/source.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::daemon::record {
class Recorder;
}

namespace livod::daemon::runtime {

// Starts the camera's capture thread. Throws livod::Error naming the sensor only for what cannot
// change by waiting (a driver that is not a camera, a V4L2 format livod cannot convert); a missing
// or refusing device is waited for. `doorbell` (may be null) is rung when a frame arrives.
// `recorder` (may be null; not started yet): the capture thread also copies every frame it keeps
// into a tap of this recorder, which writes the EuRoC folder <sensor>/ (docs/record.md).
std::unique_ptr<MeasurementSource> open_live_camera(const SensorConfig& sensor,
                                                    const LivodConfig& config,
                                                    drivers::capture::Doorbell* doorbell,
                                                    record::Recorder* recorder = nullptr);

}  // namespace livod::daemon::runtime
