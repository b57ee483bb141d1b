#pragma once
// The device side of a camera source: what V4L2 and Aravis implement. A backend runs on the
// source's capture thread (drivers/capture/device_thread.hpp): open / next_frame / service /
// close are called there only. Its counters and control mailbox are for any thread.
//
// A backend writes each frame straight into the ring slot a FrameSink hands out (converting from
// the driver's buffer on the way: the one copy), then commits the frame's metadata. When the sink
// has no slot (ring full, or the frame is decimated away) the backend skips the copy and returns
// its buffer to the driver at once.

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "core/single_writer_counter.hpp"
#include "core/spsc_ring.hpp"
#include "drivers/camera/camera_frame.hpp"

namespace livod::camera {

class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // A header over the slot for a width x height image of the ring's pixel format, or an empty
  // Mat when this frame is to be dropped (already counted by the sink).
  virtual cv::Mat acquire(int width, int height) = 0;
  // Queues the frame written into the last acquired slot.
  virtual void commit(const FrameInfo& info) = 0;
};

// Exposure and gain changes requested while streaming (applied by the capture thread between
// frames, then read back).
struct CameraControls {
  std::optional<Nanoseconds> exposure;
  std::optional<double> gain;
};

// Counters every backend keeps (snapshot).
struct CameraBackendCounters {
  std::uint64_t frames = 0;           // buffers the device delivered (complete or not)
  std::uint64_t bytes = 0;            // wire bytes of those buffers
  std::uint64_t incomplete = 0;       // dropped: missing packets, V4L2_BUF_FLAG_ERROR, aborted
  std::uint64_t sequence_gaps = 0;    // frames lost before the host (the device's frame counter)
  std::uint64_t convert_errors = 0;   // dropped: short buffer, undecodable MJPEG, wrong size
  std::uint64_t control_errors = 0;   // exposure/gain requests the camera refused
  std::uint64_t triggers = 0;         // software triggers fired
  std::int64_t exposure_ns = 0;       // current exposure (read back), 0 unknown
  double gain = std::nan("");         // current gain (read back), NaN unknown
  std::int64_t last_frame_rx_ns = 0;  // CLOCK_MONOTONIC of the newest delivered frame
};

// Single-writer atomics behind CameraBackendCounters (the capture thread writes, anyone reads).
class BackendStats {
 public:
  void add_frame(std::uint64_t bytes, std::int64_t rx_ns) {
    bump(frames_);
    publish(bytes_, bytes_.load(std::memory_order_relaxed) + bytes);
    publish(last_rx_ns_, rx_ns);
  }
  void add_incomplete() { bump(incomplete_); }
  void add_gaps(std::uint64_t n) { publish(gaps_, gaps_.load(std::memory_order_relaxed) + n); }
  void add_convert_error() { bump(convert_errors_); }
  void add_control_error() { bump(control_errors_); }
  void add_trigger() { bump(triggers_); }
  void set_exposure(Nanoseconds e) { publish(exposure_ns_, e.count()); }
  void set_gain(double g) { publish(gain_, g); }

  [[nodiscard]] CameraBackendCounters snapshot() const {
    const auto get = [](const auto& a) { return a.load(std::memory_order_relaxed); };
    CameraBackendCounters c;
    c.frames = get(frames_);
    c.bytes = get(bytes_);
    c.incomplete = get(incomplete_);
    c.sequence_gaps = get(gaps_);
    c.convert_errors = get(convert_errors_);
    c.control_errors = get(control_errors_);
    c.triggers = get(triggers_);
    c.exposure_ns = get(exposure_ns_);
    c.gain = get(gain_);
    c.last_frame_rx_ns = get(last_rx_ns_);
    return c;
  }

 private:
  alignas(kCacheLineBytes) std::atomic<std::uint64_t> frames_{0};
  std::atomic<std::uint64_t> bytes_{0};
  std::atomic<std::uint64_t> incomplete_{0};
  std::atomic<std::uint64_t> gaps_{0};
  std::atomic<std::uint64_t> convert_errors_{0};
  std::atomic<std::uint64_t> control_errors_{0};
  std::atomic<std::uint64_t> triggers_{0};
  std::atomic<std::int64_t> exposure_ns_{0};
  std::atomic<double> gain_{std::nan("")};
  std::atomic<std::int64_t> last_rx_ns_{0};
};

// A request mailbox: any thread posts, the capture thread takes (a mutex held for a copy only;
// control requests are rare and never on a hot path).
class ControlMailbox {
 public:
  void post(const CameraControls& c) {
    const std::lock_guard lock(mutex_);
    if (c.exposure) pending_.exposure = c.exposure;
    if (c.gain) pending_.gain = c.gain;
    has_.store(true, std::memory_order_release);
  }
  // Capture thread: the pending request, if any (cheap when none).
  std::optional<CameraControls> take() {
    if (!has_.load(std::memory_order_acquire)) return std::nullopt;
    const std::lock_guard lock(mutex_);
    CameraControls c = pending_;
    pending_ = {};
    has_.store(false, std::memory_order_relaxed);
    return c;
  }

 private:
  std::mutex mutex_;
  CameraControls pending_;
  std::atomic<bool> has_{false};
};

class CameraBackend {
 public:
  enum class Result : std::uint8_t { kFrame, kDropped, kIdle, kLost };

  virtual ~CameraBackend() = default;
  // Opens the device, negotiates the format, applies the configured controls and starts
  // streaming. Throws livod::Error naming the device ("V4L2 device /dev/video0 does not exist").
  virtual void open() = 0;
  virtual void close() noexcept = 0;
  // Waits up to `timeout` for one frame. kFrame: committed to the sink (or dropped by the sink);
  // kDropped: the device delivered a frame that was not usable (counted); kLost: gone.
  virtual Result next_frame(std::chrono::milliseconds timeout, FrameSink& sink) = 0;
  // Between frames on the capture thread: control requests, software triggers, readbacks.
  // false = the device is lost.
  virtual bool service() { return true; }
  [[nodiscard]] virtual std::string describe() const = 0;
  [[nodiscard]] virtual std::string loss_reason() const = 0;

  // Any thread.
  [[nodiscard]] CameraBackendCounters counters() const { return stats_.snapshot(); }
  void request(const CameraControls& c) { mailbox_.post(c); }

 protected:
  BackendStats stats_;
  ControlMailbox mailbox_;
};

}  // namespace livod::camera
