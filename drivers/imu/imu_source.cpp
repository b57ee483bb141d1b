#include "drivers/imu/imu_source.hpp"

#include <fmt/core.h>

#include <array>
#include <atomic>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"

namespace livod::imu {
namespace {

template <class T>
void publish(std::atomic<T>& a, T value) {
  a.store(value, std::memory_order_relaxed);
}

// Frames received per wait, at most.
constexpr std::size_t kCanBatch = 64;
constexpr std::int64_t kClockRefreshNs = 100'000'000;  // REALTIME -> MONOTONIC every 100 ms

drivers::DecoderCounters as_decoder_counters(const ImuDecoderCounters& c) {
  drivers::DecoderCounters d;
  d.packets = c.frames;
  d.imu_packets = c.samples;
  d.decode_errors = c.malformed + c.checksum_errors;
  d.sequence_gaps = c.sequence_gaps;
  d.incomplete_scans = c.incomplete;
  return d;
}

drivers::capture::SourceHealth make_source_health(
    const std::string& name, drivers::capture::StreamHealth stream,
    const drivers::capture::DeviceThreadCounters& device, const ImuDecoderCounters& decoder,
    std::uint64_t popped, std::string last_error) {
  drivers::capture::SourceHealth h;
  h.name = name;
  h.streams.push_back(std::move(stream));
  h.decoder = as_decoder_counters(decoder);
  h.consumer.packets = popped;
  h.device_state = drivers::capture::to_string(device.state);
  h.reconnects = device.reconnects;
  h.last_error = std::move(last_error);
  return h;
}

void copy_scheduling(const drivers::capture::DeviceThreadCounters& d,
                     drivers::capture::CaptureCounters& c) {
  c.wakeups = d.wakeups;
  c.priority = d.priority;
  c.affinity = d.affinity;
  c.priority_error = d.priority_error;
  c.affinity_error = d.affinity_error;
}

}  // namespace

std::string format_health(const ImuSourceHealth& h) {
  std::string line = drivers::capture::format_health(h.source);
  line += " | " + format_counters(h.decoder);
  if (h.bus.error_frames > 0 || h.bus.kernel_drops > 0) {
    line += fmt::format(" | bus errors {} (bus-off {}, passive {}, overflow {}, restarts {})",
                        h.bus.error_frames, h.bus.bus_off, h.bus.error_passive,
                        h.bus.controller_overflow, h.bus.restarts);
  }
  return line;
}

// ---- CAN -----------------------------------------------------------------------------------

class CanImuSource::Link final : public drivers::capture::DeviceLink {
 public:
  Link(std::string interface, SocketOpener opener, SpscRing<CanRecord>& ring,
       SpscRing<CanRecord>* tap)
      : interface_(std::move(interface)), opener_(std::move(opener)), ring_(ring), tap_(tap) {}

  void open() override {
    socket_.emplace(opener_());
    clock_.refresh();
    last_refresh_ns_ = host_now().ns;
  }
  void close() noexcept override {
    if (!socket_) return;
    retired_ = add(retired_, socket_->counters());
    socket_.reset();
  }
  Wait wait_and_read(std::chrono::milliseconds timeout) override {
    std::size_t n = 0;
    const auto status = socket_->receive(static_cast<int>(timeout.count()), batch_, n, clock_);
    std::int64_t last_rx = -1;
    for (std::size_t i = 0; i < n; ++i) {
      if (batch_[i].error) continue;
      if (ring_.try_push(batch_[i])) ++pushed_;
      if (tap_ != nullptr) tap_->try_push(batch_[i]);  // the recorder counts its overruns
      last_rx = batch_[i].rx_time_ns;
    }
    if (last_rx >= 0) publish(published_.last_rx_ns, last_rx);
    publish_counters();
    if (status == CanSocket::Status::kLost) {
      loss_reason_ = socket_->loss_reason();
      return Wait::kLost;
    }
    return last_rx >= 0 ? Wait::kData : Wait::kIdle;
  }
  bool service() override {
    const std::int64_t now = host_now().ns;
    if (now - last_refresh_ns_ > kClockRefreshNs) {
      clock_.refresh();
      last_refresh_ns_ = now;
    }
    return true;
  }
  [[nodiscard]] std::string describe() const override { return "SocketCAN " + interface_; }
  [[nodiscard]] std::string loss_reason() const override { return loss_reason_; }

  [[nodiscard]] CanBusCounters bus() const {
    CanBusCounters c;
    const auto get = [](const auto& a) { return a.load(std::memory_order_relaxed); };
    c.frames = get(published_.frames);
    c.bytes = get(published_.bytes);
    c.kernel_drops = get(published_.kernel_drops);
    c.error_frames = get(published_.error_frames);
    c.bus_off = get(published_.bus_off);
    c.error_passive = get(published_.error_passive);
    c.controller_overflow = get(published_.controller_overflow);
    c.restarts = get(published_.restarts);
    c.protocol_errors = get(published_.protocol_errors);
    c.receive_errors = get(published_.receive_errors);
    c.missing_timestamps = get(published_.missing_timestamps);
    return c;
  }
  [[nodiscard]] std::uint64_t pushed() const {
    return published_.pushed.load(std::memory_order_relaxed);
  }
  [[nodiscard]] std::int64_t last_rx_ns() const {
    return published_.last_rx_ns.load(std::memory_order_relaxed);
  }

 private:
  struct alignas(kCacheLineBytes) Published {
    std::atomic<std::uint64_t> frames{0}, bytes{0}, kernel_drops{0}, error_frames{0}, bus_off{0},
        error_passive{0}, controller_overflow{0}, restarts{0}, protocol_errors{0},
        receive_errors{0}, missing_timestamps{0}, pushed{0};
    std::atomic<std::int64_t> last_rx_ns{0};
  };

  static CanBusCounters add(const CanBusCounters& a, const CanBusCounters& b) {
    CanBusCounters s;
    s.frames = a.frames + b.frames;
    s.bytes = a.bytes + b.bytes;
    s.kernel_drops = a.kernel_drops + b.kernel_drops;
    s.error_frames = a.error_frames + b.error_frames;
    s.bus_off = a.bus_off + b.bus_off;
    s.error_passive = a.error_passive + b.error_passive;
    s.controller_overflow = a.controller_overflow + b.controller_overflow;
    s.restarts = a.restarts + b.restarts;
    s.protocol_errors = a.protocol_errors + b.protocol_errors;
    s.receive_errors = a.receive_errors + b.receive_errors;
    s.missing_timestamps = a.missing_timestamps + b.missing_timestamps;
    return s;
  }

  void publish_counters() {
    const CanBusCounters c = add(retired_, socket_->counters());
    publish(published_.frames, c.frames);
    publish(published_.bytes, c.bytes);
    publish(published_.kernel_drops, c.kernel_drops);
    publish(published_.error_frames, c.error_frames);
    publish(published_.bus_off, c.bus_off);
    publish(published_.error_passive, c.error_passive);
    publish(published_.controller_overflow, c.controller_overflow);
    publish(published_.restarts, c.restarts);
    publish(published_.protocol_errors, c.protocol_errors);
    publish(published_.receive_errors, c.receive_errors);
    publish(published_.missing_timestamps, c.missing_timestamps);
    publish(published_.pushed, pushed_);
  }

  std::string interface_;
  SocketOpener opener_;
  SpscRing<CanRecord>& ring_;
  SpscRing<CanRecord>* tap_;
  std::optional<CanSocket> socket_;
  RealtimeToMonotonic clock_;
  std::int64_t last_refresh_ns_ = 0;
  std::array<CanRecord, kCanBatch> batch_{};
  CanBusCounters retired_;  // totals of the sockets closed so far
  std::uint64_t pushed_ = 0;
  std::string loss_reason_;
  Published published_;
};

CanImuSource::CanImuSource(const CanImuSourceConfig& config, std::unique_ptr<CanImuDecoder> decoder,
                           SocketOpener opener)
    : name_(config.name),
      decoder_(std::move(decoder)),
      ring_(config.ring_capacity),
      monitor_(config.socket.interface.empty() ? "can" : config.socket.interface,
               config.timing.stale_after, config.timing.rate_window) {
  if (!decoder_) throw std::invalid_argument("CanImuSource: null decoder");
  CanSocketConfig socket = config.socket;
  if (socket.ids.empty()) socket.ids = decoder_->frame_ids();
  if (!opener) opener = [socket] { return CanSocket::open(socket); };
  link_ = std::make_unique<Link>(socket.interface, std::move(opener), ring_, config.tap);
  drivers::capture::DeviceThreadConfig thread = config.thread;
  if (thread.thread_name.empty()) thread.thread_name = "can:" + config.name;
  thread_ = std::make_unique<drivers::capture::DeviceThread>(*link_, thread);
}

CanImuSource::~CanImuSource() {
  stop();
}

void CanImuSource::stop() {
  if (thread_) thread_->stop();
}

std::size_t CanImuSource::poll(const ImuSink& sink, std::size_t max_frames) {
  std::size_t n = 0;
  while (n < max_frames) {
    CanRecord* r = ring_.front();
    if (r == nullptr) break;
    decoder_->on_frame(*r, sink);
    ring_.pop();
    ++n;
  }
  popped_ += n;
  return n;
}

std::optional<HostTime> CanImuSource::next_rx() {
  const CanRecord* r = ring_.front();
  if (r == nullptr) return std::nullopt;
  return HostTime(r->rx_time_ns);
}

CanBusCounters CanImuSource::bus_counters() const {
  return link_->bus();
}

drivers::capture::DeviceThreadCounters CanImuSource::device_counters() const {
  return thread_->counters();
}

ImuSourceHealth CanImuSource::update_health(HostTime now) {
  ImuSourceHealth h;
  h.bus = link_->bus();
  h.device = thread_->counters();
  h.decoder = decoder_->counters();
  h.ring_overruns = ring_.overruns();
  drivers::capture::CaptureCounters cc;
  cc.datagrams = h.bus.frames;
  cc.bytes = h.bus.bytes;
  cc.pushed = link_->pushed();
  cc.ring_overruns = h.ring_overruns;
  cc.kernel_drops = h.bus.kernel_drops;
  cc.receive_errors = h.bus.receive_errors;
  cc.missing_timestamps = h.bus.missing_timestamps;
  cc.last_rx_ns = link_->last_rx_ns();
  copy_scheduling(h.device, cc);
  h.source = make_source_health(name_, monitor_.update(now, cc), h.device, h.decoder, popped_,
                                thread_->last_error());
  return h;
}

// ---- serial / USB --------------------------------------------------------------------------

class SerialImuSource::Link final : public drivers::capture::DeviceLink {
 public:
  Link(std::string path, PortOpener opener, drivers::capture::PacketRing& ring,
       drivers::capture::PacketRing* tap, std::size_t chunk_bytes)
      : path_(std::move(path)),
        opener_(std::move(opener)),
        ring_(ring),
        tap_(tap),
        chunk_(chunk_bytes) {}

  void open() override { port_ = opener_(); }
  void close() noexcept override { port_.reset(); }
  Wait wait_and_read(std::chrono::milliseconds timeout) override {
    const ByteReadResult r = port_->read(chunk_, static_cast<int>(timeout.count()));
    if (r.status == ByteReadResult::Status::kLost) {
      loss_reason_ = port_->loss_reason();
      return Wait::kLost;
    }
    if (r.status == ByteReadResult::Status::kIdle) return Wait::kIdle;
    ++reads_;
    bytes_ += r.bytes;
    if (ring_.try_push({chunk_.data(), r.bytes}, HostTime(r.rx_time_ns), 0)) ++pushed_;
    if (tap_ != nullptr) tap_->try_push({chunk_.data(), r.bytes}, HostTime(r.rx_time_ns), 0);
    publish(published_.reads, reads_);
    publish(published_.bytes, bytes_);
    publish(published_.pushed, pushed_);
    publish(published_.last_rx_ns, r.rx_time_ns);
    return Wait::kData;
  }
  [[nodiscard]] std::string describe() const override {
    return port_ ? port_->describe() : "serial IMU " + path_;
  }
  [[nodiscard]] std::string loss_reason() const override { return loss_reason_; }

  drivers::capture::CaptureCounters counters() const {
    const auto get = [](const auto& a) { return a.load(std::memory_order_relaxed); };
    drivers::capture::CaptureCounters c;
    c.datagrams = get(published_.reads);
    c.bytes = get(published_.bytes);
    c.pushed = get(published_.pushed);
    c.last_rx_ns = get(published_.last_rx_ns);
    c.ring_overruns = ring_.overruns();
    return c;
  }

 private:
  struct alignas(kCacheLineBytes) Published {
    std::atomic<std::uint64_t> reads{0}, bytes{0}, pushed{0};
    std::atomic<std::int64_t> last_rx_ns{0};
  };

  std::string path_;
  PortOpener opener_;
  drivers::capture::PacketRing& ring_;
  drivers::capture::PacketRing* tap_;
  std::vector<std::byte> chunk_;
  std::unique_ptr<BytePort> port_;
  std::uint64_t reads_ = 0;
  std::uint64_t bytes_ = 0;
  std::uint64_t pushed_ = 0;
  std::string loss_reason_;
  Published published_;
};

SerialImuSource::SerialImuSource(const SerialImuSourceConfig& config,
                                 std::unique_ptr<StreamImuDecoder> decoder, PortOpener opener)
    : name_(config.name),
      decoder_(std::move(decoder)),
      ring_(config.ring_capacity, config.chunk_bytes),
      monitor_("serial", config.timing.stale_after, config.timing.rate_window) {
  if (!decoder_) throw std::invalid_argument("SerialImuSource: null decoder");
  if (!opener) {
    const std::string path = config.path;
    const int baud = config.baud_rate;
    if (const auto usb = parse_usb_selector(path)) {
      opener = [selector = *usb]() -> std::unique_ptr<BytePort> {
        return std::make_unique<UsbBulkPort>(selector);
      };
    } else {
      opener = [path, baud]() -> std::unique_ptr<BytePort> {
        return std::make_unique<SerialPort>(path, baud);
      };
    }
  }
  if (config.tap != nullptr && config.tap->max_payload_bytes() < config.chunk_bytes) {
    throw std::invalid_argument("SerialImuSource: tap slots smaller than a read");
  }
  link_ =
      std::make_unique<Link>(config.path, std::move(opener), ring_, config.tap, config.chunk_bytes);
  drivers::capture::DeviceThreadConfig thread = config.thread;
  if (thread.thread_name.empty()) thread.thread_name = "imu:" + config.name;
  thread_ = std::make_unique<drivers::capture::DeviceThread>(*link_, thread);
}

SerialImuSource::~SerialImuSource() {
  stop();
}

void SerialImuSource::stop() {
  if (thread_) thread_->stop();
}

std::size_t SerialImuSource::poll(const ImuSink& sink, std::size_t max_chunks) {
  std::size_t n = 0;
  while (n < max_chunks) {
    const drivers::capture::RawPacket* p = ring_.front();
    if (p == nullptr) break;
    decoder_->on_bytes(p->payload, p->rx.ns, sink);
    ring_.pop();
    ++n;
  }
  popped_ += n;
  return n;
}

std::optional<HostTime> SerialImuSource::next_rx() {
  const drivers::capture::RawPacket* p = ring_.front();
  if (p == nullptr) return std::nullopt;
  return p->rx;
}

drivers::capture::DeviceThreadCounters SerialImuSource::device_counters() const {
  return thread_->counters();
}

drivers::capture::CaptureCounters SerialImuSource::capture_counters() const {
  drivers::capture::CaptureCounters c = link_->counters();
  copy_scheduling(thread_->counters(), c);
  return c;
}

ImuSourceHealth SerialImuSource::update_health(HostTime now) {
  ImuSourceHealth h;
  h.device = thread_->counters();
  h.decoder = decoder_->counters();
  h.ring_overruns = ring_.overruns();
  drivers::capture::CaptureCounters cc = link_->counters();
  copy_scheduling(h.device, cc);
  h.source = make_source_health(name_, monitor_.update(now, cc), h.device, h.decoder, popped_,
                                thread_->last_error());
  return h;
}

}  // namespace livod::imu
