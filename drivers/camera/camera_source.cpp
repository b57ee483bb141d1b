#include "drivers/camera/camera_source.hpp"

#include <fmt/core.h>

#include <cstring>
#include <stdexcept>

namespace livod::camera {

// The capture-thread side: DeviceLink over the backend, FrameSink over the ring.
class CameraSource::Link final : public drivers::capture::DeviceLink, public FrameSink {
 public:
  Link(CameraBackend& backend, FrameRing& ring, FrameRing* tap, PixelFormat format, int decimation)
      : backend_(backend), ring_(ring), tap_(tap), format_(format), decimation_(decimation) {}

  // DeviceLink
  void open() override { backend_.open(); }
  void close() noexcept override { backend_.close(); }
  Wait wait_and_read(std::chrono::milliseconds timeout) override {
    switch (backend_.next_frame(timeout, *this)) {
      case CameraBackend::Result::kFrame:
      case CameraBackend::Result::kDropped:
        return Wait::kData;  // the camera is alive either way
      case CameraBackend::Result::kIdle:
        return Wait::kIdle;
      case CameraBackend::Result::kLost:
        return Wait::kLost;
    }
    return Wait::kIdle;
  }
  bool service() override { return backend_.service(); }
  [[nodiscard]] std::string describe() const override { return backend_.describe(); }
  [[nodiscard]] std::string loss_reason() const override { return backend_.loss_reason(); }

  // FrameSink
  cv::Mat acquire(int width, int height) override {
    const bool keep = (seen_++ % static_cast<std::uint64_t>(decimation_)) == 0;
    if (!keep) {
      decimated_.store(decimated_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      return {};
    }
    const std::size_t stride = static_cast<std::size_t>(width) * bytes_per_pixel(format_);
    if (width <= 0 || height <= 0 ||
        stride * static_cast<std::size_t>(height) > ring_.slot_bytes()) {
      return {};  // larger than configured: the backend counts a convert error
    }
    const std::span<std::byte> slot = ring_.begin_write();
    if (slot.empty()) return {};  // full: counted by the ring
    slot_ = slot.data();
    return cv::Mat(height, width, cv_type(format_), slot.data(), stride);
  }
  void commit(const FrameInfo& info) override {
    FrameInfo stamped = info;
    stamped.ring_push = host_now();
    if (tap_ != nullptr) {
      // The recorder's copy; a full tap drops it (counted by the tap) and nothing else.
      const std::size_t bytes = static_cast<std::size_t>(info.height) * info.stride;
      const std::span<std::byte> copy =
          bytes <= tap_->slot_bytes() ? tap_->begin_write() : std::span<std::byte>();
      if (!copy.empty()) {
        std::memcpy(copy.data(), slot_, bytes);
        tap_->commit(stamped);
      }
    }
    ring_.commit(stamped);
  }

  [[nodiscard]] std::uint64_t decimated() const {
    return decimated_.load(std::memory_order_relaxed);
  }

 private:
  CameraBackend& backend_;
  FrameRing& ring_;
  FrameRing* tap_;
  const std::byte* slot_ = nullptr;  // the ring slot acquire() handed out
  PixelFormat format_;
  int decimation_;
  std::uint64_t seen_ = 0;
  std::atomic<std::uint64_t> decimated_{0};
};

std::string format_health(const CameraHealth& h) {
  std::string line = drivers::capture::format_health(h.source);
  line += fmt::format(" | frames {} incomplete {} gaps {} convert errors {} ring overruns {}",
                      h.backend.frames, h.backend.incomplete, h.backend.sequence_gaps,
                      h.backend.convert_errors, h.ring_overruns);
  if (h.backend.exposure_ns > 0) {
    line += fmt::format(" exposure {:.3f} ms", static_cast<double>(h.backend.exposure_ns) * 1e-6);
  }
  if (h.clock) {
    line += fmt::format(" clock {} skew {:.1f} ppm jitter {} us", to_string(h.clock->quality),
                        h.clock->skew_ppm, h.clock->jitter.count() / 1000);
  }
  return line;
}

CameraSource::CameraSource(const CameraSourceConfig& config, std::unique_ptr<CameraBackend> backend)
    : name_(config.name),
      backend_(std::move(backend)),
      ring_(config.ring_capacity, static_cast<std::size_t>(std::max(config.width, 1)) *
                                      static_cast<std::size_t>(std::max(config.height, 1)) *
                                      static_cast<std::size_t>(bytes_per_pixel(config.format))),
      clock_(config.clock),
      monitor_("frames", config.stale_after, config.rate_window) {
  if (!backend_) throw std::invalid_argument("CameraSource: null backend");
  if (config.width <= 0 || config.height <= 0) {
    throw std::invalid_argument("CameraSource: width and height must be > 0");
  }
  link_ = std::make_unique<Link>(*backend_, ring_, config.tap, config.format,
                                 std::max(config.decimation, 1));
  drivers::capture::DeviceThreadConfig thread = config.thread;
  if (thread.thread_name.empty()) thread.thread_name = "cam:" + config.name;
  if (thread.silence_timeout.count() == 0 && config.reopen_on_silence) {
    thread.silence_timeout = config.stale_after;
  }
  thread_ = std::make_unique<drivers::capture::DeviceThread>(*link_, thread);
}

CameraSource::~CameraSource() {
  stop();
}

void CameraSource::stop() {
  if (thread_) thread_->stop();
}

void CameraSource::set_exposure(Nanoseconds exposure) {
  backend_->request({.exposure = exposure});
}

void CameraSource::set_gain(double gain) {
  backend_->request({.gain = gain});
}

drivers::capture::DeviceThreadCounters CameraSource::device_counters() const {
  return thread_->counters();
}

std::size_t CameraSource::poll(const FrameCallback& callback, std::size_t max_frames) {
  std::size_t n = 0;
  CameraFrame frame;
  while (n < max_frames) {
    const FrameRing::Entry* e = ring_.front();
    if (e == nullptr) break;
    frame.info = e->info;
    frame.image = cv::Mat(e->info.height, e->info.width, cv_type(e->info.format),
                          const_cast<std::byte*>(e->pixels.data()), e->info.stride);
    clock_.map(frame);
    frame.index = delivered_++;
    if (callback) callback(frame);
    frame.image = cv::Mat();
    ring_.pop();
    ++n;
  }
  return n;
}

std::optional<HostTime> CameraSource::next_rx() {
  const FrameRing::Entry* e = ring_.front();
  if (e == nullptr) return std::nullopt;
  return e->info.host_rx;
}

CameraHealth CameraSource::update_health(HostTime now) {
  CameraHealth h;
  h.device = thread_->counters();
  h.backend = backend_->counters();
  h.ring_overruns = ring_.overruns();
  h.decimated = link_->decimated();
  h.delivered = delivered_;
  h.clock = clock_.stats();
  drivers::capture::CaptureCounters cc;
  cc.datagrams = h.backend.frames;
  cc.bytes = h.backend.bytes;
  // Counters are read one by one while frames flow: never let the difference go below 0.
  const std::uint64_t not_pushed =
      h.backend.incomplete + h.backend.convert_errors + h.ring_overruns + h.decimated;
  cc.pushed = h.backend.frames > not_pushed ? h.backend.frames - not_pushed : 0;
  cc.ring_overruns = h.ring_overruns;
  cc.last_rx_ns = h.backend.last_frame_rx_ns;
  cc.wakeups = h.device.wakeups;
  cc.priority = h.device.priority;
  cc.affinity = h.device.affinity;
  cc.priority_error = h.device.priority_error;
  cc.affinity_error = h.device.affinity_error;
  drivers::capture::SourceHealth& s = h.source;
  s.name = name_;
  s.streams.push_back(monitor_.update(now, cc));
  s.decoder.packets = h.backend.frames;
  s.decoder.decode_errors = h.backend.incomplete + h.backend.convert_errors;
  s.decoder.sequence_gaps = h.backend.sequence_gaps;
  s.consumer.packets = h.delivered;
  s.device_state = drivers::capture::to_string(h.device.state);
  s.reconnects = h.device.reconnects;
  s.last_error = thread_->last_error();
  return h;
}

}  // namespace livod::camera
