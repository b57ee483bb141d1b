#include "daemon/runtime/live_camera_source.hpp"

#include <fmt/core.h>
#include <spdlog/spdlog.h>

#include "core/image.hpp"
#include "daemon/devices/device_sources.hpp"
#include "daemon/record/recorder.hpp"

namespace livod::daemon::runtime {
namespace {

class LiveCamera final : public MeasurementSource {
 public:
  LiveCamera(const SensorConfig& sensor, std::unique_ptr<camera::CameraSource> camera)
      : name_(sensor.name), camera_(std::move(camera)) {
    const auto d = camera_->device_counters();
    if (d.opens == 0) {
      spdlog::error("sensor '{}': {}; waiting for it (retried every second)", name_,
                    camera_->update_health(host_now()).source.last_error);
    }
  }
  ~LiveCamera() override { stop(); }

  std::optional<std::int64_t> peek_time() override {
    const auto rx = camera_->next_rx();
    if (!rx) return std::nullopt;
    return rx->ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    camera_->poll(
        [&](const camera::CameraFrame& f) {
          // The ring slot is reused once this returns: the estimator gets its own copy.
          if (sinks.on_image) sinks.on_image(camera::to_image_frame(f));
        },
        1);
  }

  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  bool exhausted() override { return stopped_ && !camera_->next_rx(); }

  void stop() override {
    if (stopped_) return;
    stopped_ = true;
    camera_->stop();
  }

  std::optional<drivers::capture::SourceHealth> health(HostTime now) override {
    return camera_->update_health(now).source;
  }

  [[nodiscard]] std::string summary() const override {
    const auto b = camera_->backend_counters();
    const auto d = camera_->device_counters();
    return fmt::format(
        "{}: frames {}, incomplete {}, sequence gaps {}, convert errors {}, ring overruns {}; "
        "device {}, opens {}, losses {}, reconnects {}",
        camera_->backend().describe(), b.frames, b.incomplete, b.sequence_gaps, b.convert_errors,
        camera_->ring_overruns(), drivers::capture::to_string(d.state), d.opens, d.losses,
        d.reconnects);
  }

  [[nodiscard]] std::vector<SourceThread> threads() const override {
    const camera::CameraSource* c = camera_.get();
    return {{name_ + ".frames", [c] { return c->device_counters().wakeups; }}};
  }

  [[nodiscard]] bool delivers_mapped_images() const override { return true; }

  [[nodiscard]] std::optional<ClockDomainStats> clock_stats() const override {
    return camera_->clock_stats();
  }

 private:
  std::string name_;
  std::unique_ptr<camera::CameraSource> camera_;
  bool stopped_ = false;
};

}  // namespace

std::unique_ptr<MeasurementSource> open_live_camera(const SensorConfig& sensor,
                                                    const LivodConfig& config,
                                                    drivers::capture::Doorbell* doorbell,
                                                    record::Recorder* recorder) {
  devices::DeviceOpenOptions options;
  options.wait_for_device = true;
  options.doorbell = doorbell;
  if (recorder != nullptr) {
    options.camera_tap = &recorder->add_camera_stream(
        {sensor.name, devices::camera_frame_bytes(sensor), devices::camera_clock_config(sensor)});
  }
  return std::make_unique<LiveCamera>(sensor, devices::open_camera_source(sensor, config, options));
}

}  // namespace livod::daemon::runtime
