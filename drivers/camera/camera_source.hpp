#pragma once
// A live camera, with the same contract as the LiDAR sources (drivers/capture/live_source.hpp):
//
//   camera --V4L2 / Aravis--> capture thread (CameraBackend) --FrameRing (pixels + FrameInfo)-->
//        poll() on the consumer thread: CameraClock -> CameraFrame -> your callback
//
// * One capture thread per camera (drivers/capture/device_thread.hpp) with an optional SCHED_FIFO
//   priority and CPU. It writes each frame into a pre-allocated ring slot (the one copy), never
//   allocates in steady state (MJPEG decoding excepted, see pixel_convert.hpp), never logs.
// * A full ring drops the newest frame and counts it (FrameRing::overruns); `decimation` n keeps
//   every n-th delivered frame and skips the copy of the others. With a recorder's `tap`, each kept
//   frame is copied into the tap as well (one memcpy on the capture thread; the recorder thread
//   encodes it).
// * A camera that stops delivering for `stale_after` (or reports an error: V4L2 ENODEV, GigE
//   control lost) is LOST: closed, and reopened every `reopen_interval` until it is back. A
//   camera missing at construction throws livod::Error naming it.
// * Exposure and gain can be changed while streaming (set_exposure / set_gain, any thread); the
//   capture thread applies them between frames and reads them back.
//
// Threading contract: poll() and update_health() belong to one consumer thread (the scheduler);
// counters(), set_exposure(), set_gain() may be called from any thread; stop() or the destructor
// joins the capture thread.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "drivers/camera/camera_backend.hpp"
#include "drivers/camera/camera_clock.hpp"
#include "drivers/camera/frame_ring.hpp"
#include "drivers/capture/device_thread.hpp"
#include "drivers/capture/health.hpp"

namespace livod::camera {

struct CameraSourceConfig {
  std::string name;  // the sensor's name (health, thread name)
  int width = 0;     // the largest frame the ring holds (the configured image size)
  int height = 0;
  PixelFormat format = PixelFormat::kMono8;
  std::size_t ring_capacity = 8;  // frames; e.g. 8 x 1280 x 1024 mono8 = 10.5 MB
  int decimation = 1;             // keep every n-th frame
  CameraClockConfig clock;
  drivers::capture::DeviceThreadConfig
      thread;  // silence_timeout: set from stale_after unless given
  Nanoseconds stale_after{std::chrono::seconds(1)};
  Nanoseconds rate_window{std::chrono::seconds(5)};
  // Hardware-triggered cameras are silent while the trigger is: do not reopen on silence.
  bool reopen_on_silence = true;
  // Recording (`livod record`, outputs.record): the capture thread also copies every frame it
  // keeps (after decimation) into this ring, slots of at least width x height x bytes per pixel;
  // a full tap drops the frame there and counts it, never blocks. May be null; must outlive the
  // source.
  FrameRing* tap = nullptr;
};

struct CameraHealth {
  drivers::capture::SourceHealth
      source;  // one stream "frames": rate, STALE, drops; device state, reconnects
  drivers::capture::DeviceThreadCounters device;
  CameraBackendCounters backend;
  std::uint64_t ring_overruns = 0;
  std::uint64_t decimated = 0;
  std::uint64_t delivered = 0;  // frames handed to poll() callbacks
  std::optional<ClockDomainStats> clock;
};

[[nodiscard]] std::string format_health(const CameraHealth& health);

class CameraSource {
 public:
  using FrameCallback = std::function<void(const CameraFrame&)>;

  // Opens the camera (throws livod::Error naming it) and starts the capture thread.
  CameraSource(const CameraSourceConfig& config, std::unique_ptr<CameraBackend> backend);
  ~CameraSource();
  CameraSource(const CameraSource&) = delete;
  CameraSource& operator=(const CameraSource&) = delete;

  // Consumer thread: maps and hands out up to max_frames queued frames (each pixel view valid
  // during its callback only); returns how many.
  std::size_t poll(const FrameCallback& callback, std::size_t max_frames = SIZE_MAX);
  // Consumer thread: the receive time (host_rx) of the oldest queued frame; nullopt when none is.
  [[nodiscard]] std::optional<HostTime> next_rx();
  // Consumer thread, at the health cadence.
  CameraHealth update_health(HostTime now);
  // Consumer thread: the camera clock's statistics (nullopt until the first frame chose it).
  [[nodiscard]] std::optional<ClockDomainStats> clock_stats() const { return clock_.stats(); }

  // Any thread.
  void set_exposure(Nanoseconds exposure);
  void set_gain(double gain);
  [[nodiscard]] CameraBackendCounters backend_counters() const { return backend_->counters(); }
  [[nodiscard]] drivers::capture::DeviceThreadCounters device_counters() const;
  [[nodiscard]] std::uint64_t ring_overruns() const { return ring_.overruns(); }
  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] const CameraBackend& backend() const { return *backend_; }

  void stop();

 private:
  class Link;
  std::string name_;
  std::unique_ptr<CameraBackend> backend_;
  FrameRing ring_;
  CameraClock clock_;
  std::unique_ptr<Link> link_;
  drivers::capture::StreamMonitor monitor_;
  std::uint64_t delivered_ = 0;
  std::unique_ptr<drivers::capture::DeviceThread> thread_;  // last: joined first
};

}  // namespace livod::camera
