#include "daemon/runtime/paced_sources.hpp"

#include <algorithm>
#include <stop_token>
#include <thread>

#include "core/error.hpp"
#include "core/image.hpp"
#include "daemon/replay/decoder_factory.hpp"
#include "drivers/capture/health.hpp"
#include "drivers/capture/packet_ring.hpp"
#include "drivers/capture/pcap_pacer.hpp"
#include "drivers/capture/stream_consumer.hpp"

namespace livod::daemon::runtime {
namespace {

// Ring slots for recorded datagrams: the largest UDP payload (a recording may hold any profile).
constexpr std::size_t kSlotBytes = 65536;
constexpr std::size_t kRingCapacity = 1024;

class PacedPcap final : public MeasurementSource {
 public:
  PacedPcap(const SensorConfig& sensor, const std::filesystem::path& file,
            const std::vector<std::uint16_t>& ports, const PaceSchedule& schedule)
      : file_(file), monitor_("pcap", Nanoseconds(500'000'000), Nanoseconds(5'000'000'000)) {
    auto decoder = replay::make_lidar_decoder(sensor);
    const std::vector<std::uint16_t> routed = ports.empty() ? decoder->default_ports() : ports;
    std::vector<drivers::capture::PacketRing*> rings;
    for (const std::uint16_t port : routed) {
      rings_.push_back(std::make_unique<drivers::capture::PacketRing>(kRingCapacity, kSlotBytes));
      routes_.push_back(drivers::capture::RingRoute{port, rings_.back().get()});
      rings.push_back(rings_.back().get());
    }
    consumer_ =
        std::make_unique<drivers::capture::StreamConsumer>(std::move(decoder), std::move(rings));
    drivers::capture::PaceOptions po;
    po.epoch_record_ns = schedule.t0_record_ns;
    po.epoch = schedule.start;
    po.progress = &progress_;
    po.doorbell = schedule.doorbell;
    pacer_ = std::jthread([this, po](const std::stop_token& stop) {
      try {
        result_ = drivers::capture::push_pcap_paced(file_, routes_, po, stop);
      } catch (const std::exception& e) {
        // Reported by summary(); the source then ends like a recording that ended.
        error_ = e.what();
        progress_.done.store(true, std::memory_order_release);
      }
    });
  }

  ~PacedPcap() override { stop(); }

  std::optional<std::int64_t> peek_time() override {
    const auto rx = consumer_->next_rx();
    if (!rx) return std::nullopt;
    return rx->ns;
  }
  void deliver(const drivers::DecoderSinks& sinks) override { consumer_->poll(sinks, 1); }
  void finish(const drivers::DecoderSinks& sinks) override { consumer_->flush(sinks); }
  bool exhausted() override {
    return progress_.done.load(std::memory_order_acquire) && !consumer_->next_rx();
  }
  void stop() override {
    if (pacer_.joinable()) {
      pacer_.request_stop();
      pacer_.join();
    }
  }

  std::optional<drivers::capture::SourceHealth> health(HostTime now) override {
    drivers::capture::CaptureCounters c;
    c.pushed = progress_.delivered.load(std::memory_order_relaxed);
    c.datagrams = c.pushed + progress_.failed.load(std::memory_order_relaxed);
    for (const auto& r : rings_) c.ring_overruns += r->overruns();
    c.last_rx_ns = progress_.last_delivery_ns.load(std::memory_order_relaxed);
    drivers::capture::SourceHealth h;
    h.name = file_.filename().string();
    h.streams.push_back(monitor_.update(now, c));
    h.decoder = consumer_->decoder_counters();
    h.consumer = consumer_->counters();
    if (!error_.empty() && progress_.done.load(std::memory_order_acquire)) h.last_error = error_;
    return h;
  }

  [[nodiscard]] io::InputLossLog input_losses() const override {
    if (!progress_.done.load(std::memory_order_acquire)) return {};
    return result_.losses;
  }

  [[nodiscard]] std::string summary() const override {
    const auto c = consumer_->decoder_counters();
    std::uint64_t overruns = 0;
    for (const auto& r : rings_) overruns += r->overruns();
    std::string s =
        "paced pcap: datagrams " +
        std::to_string(progress_.delivered.load(std::memory_order_relaxed)) + ", ring overruns " +
        std::to_string(overruns) + "; packets " + std::to_string(c.packets) + ", scans " +
        std::to_string(c.scans) + ", points " + std::to_string(c.points) + ", sequence gaps " +
        std::to_string(c.sequence_gaps) + ", decode errors " + std::to_string(c.decode_errors);
    if (!error_.empty() && progress_.done.load(std::memory_order_acquire)) {
      s += "; stopped: " + error_;
    }
    return s;
  }

 private:
  std::filesystem::path file_;
  std::vector<std::unique_ptr<drivers::capture::PacketRing>> rings_;
  std::vector<drivers::capture::RingRoute> routes_;
  std::unique_ptr<drivers::capture::StreamConsumer> consumer_;
  drivers::capture::StreamMonitor monitor_;
  drivers::capture::PaceProgress progress_;
  // Written by the pacer before `done` (release), read after (acquire).
  std::string error_;
  drivers::capture::PaceResult result_;
  std::jthread pacer_;  // last: stopped and joined before the rings go
};

class PacedRecording final : public MeasurementSource {
 public:
  PacedRecording(std::unique_ptr<MeasurementSource> recorded, const PaceSchedule& schedule)
      : recorded_(std::move(recorded)),
        schedule_(schedule),
        shift_(schedule.start.ns - schedule.t0_record_ns) {}

  std::optional<std::int64_t> peek_time() override {
    const auto t = recorded_->peek_time();
    if (!t) return std::nullopt;
    const HostTime due = schedule_.due(*t);
    if (host_now() < due) return std::nullopt;
    return due.ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    if (!shifted_.on_scan) {
      // The recorded source stamps receive times from its file; move them onto the schedule.
      shifted_.on_scan = [this](const LidarScan& scan) {
        LidarScan s = scan;
        s.start.host += Nanoseconds(shift_);
        if (target_->on_scan) target_->on_scan(s);
      };
      shifted_.on_imu = [this](const ImuSample& sample) {
        ImuSample s = sample;
        s.stamp.host += Nanoseconds(shift_);
        if (target_->on_imu) target_->on_imu(s);
      };
      shifted_.on_image = [this](const ImageFrame& frame) {
        ImageFrame f = frame;  // shares the pixels
        f.stamp.host += Nanoseconds(shift_);
        if (target_->on_image) target_->on_image(f);
      };
    }
    target_ = &sinks;
    recorded_->deliver(shifted_);
  }

  void finish(const drivers::DecoderSinks& sinks) override {
    if (!shifted_.on_scan) {
      recorded_->finish(sinks);  // nothing was delivered: nothing to shift
      return;
    }
    target_ = &sinks;
    recorded_->finish(shifted_);
  }
  bool exhausted() override { return !recorded_->peek_time(); }
  [[nodiscard]] std::string summary() const override { return "paced " + recorded_->summary(); }
  [[nodiscard]] io::InputLossLog input_losses() const override { return recorded_->input_losses(); }
  [[nodiscard]] std::vector<std::string> notes() const override { return recorded_->notes(); }
  [[nodiscard]] std::optional<double> fraction_done() const override {
    return recorded_->fraction_done();
  }

 private:
  std::unique_ptr<MeasurementSource> recorded_;
  PaceSchedule schedule_;
  std::int64_t shift_;
  drivers::DecoderSinks shifted_;
  const drivers::DecoderSinks* target_ = nullptr;
};

}  // namespace

std::unique_ptr<MeasurementSource> open_paced_pcap(const SensorConfig& sensor,
                                                   const std::filesystem::path& file,
                                                   const std::vector<std::uint16_t>& ports,
                                                   const PaceSchedule& schedule) {
  return std::make_unique<PacedPcap>(sensor, file, ports, schedule);
}

std::unique_ptr<MeasurementSource> pace_recording(std::unique_ptr<MeasurementSource> recorded,
                                                  const PaceSchedule& schedule) {
  return std::make_unique<PacedRecording>(std::move(recorded), schedule);
}

}  // namespace livod::daemon::runtime
