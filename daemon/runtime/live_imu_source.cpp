#include "daemon/runtime/live_imu_source.hpp"

#include <fmt/core.h>
#include <spdlog/spdlog.h>

#include <variant>

#include "core/error.hpp"
#include "daemon/devices/device_sources.hpp"
#include "daemon/record/recorder.hpp"

namespace livod::daemon::runtime {
namespace {

// CanImuSource and SerialImuSource have the same consumer interface.
template <class Device>
class LiveImu final : public MeasurementSource {
 public:
  LiveImu(const SensorConfig& sensor, std::string stream, std::unique_ptr<Device> device)
      : name_(sensor.name), stream_(std::move(stream)), device_(std::move(device)) {
    if (device_->device_counters().opens == 0) {
      spdlog::error("sensor '{}': {}; waiting for it (retried every second)", name_,
                    device_->update_health(host_now()).source.last_error);
    }
  }
  ~LiveImu() override { stop(); }

  std::optional<std::int64_t> peek_time() override {
    const auto rx = device_->next_rx();
    if (!rx) return std::nullopt;
    return rx->ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    device_->poll(
        [&](const ImuSample& s) {
          if (sinks.on_imu) sinks.on_imu(s);
        },
        1);
  }

  // A partial message or sample held by the decoder is not a measurement: nothing to flush.
  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  bool exhausted() override { return stopped_ && !device_->next_rx(); }

  void stop() override {
    if (stopped_) return;
    stopped_ = true;
    device_->stop();
  }

  std::optional<drivers::capture::SourceHealth> health(HostTime now) override {
    return device_->update_health(now).source;
  }

  [[nodiscard]] std::string summary() const override {
    const auto d = device_->device_counters();
    return fmt::format("{} {}: {}; device {}, opens {}, losses {}, reconnects {}", stream_,
                       device_->decoder().model_name(),
                       imu::format_counters(device_->decoder().counters()),
                       drivers::capture::to_string(d.state), d.opens, d.losses, d.reconnects);
  }

  [[nodiscard]] std::vector<SourceThread> threads() const override {
    const Device* d = device_.get();
    return {{name_ + "." + stream_, [d] { return d->device_counters().wakeups; }}};
  }

 private:
  std::string name_;
  std::string stream_;
  std::unique_ptr<Device> device_;
  bool stopped_ = false;
};

}  // namespace

std::unique_ptr<MeasurementSource> open_live_imu(const SensorConfig& sensor,
                                                 const LivodConfig& config,
                                                 drivers::capture::Doorbell* doorbell,
                                                 record::Recorder* recorder) {
  devices::DeviceOpenOptions options;
  options.wait_for_device = true;
  options.doorbell = doorbell;
  if (sensor.driver == Driver::can_imu) {
    if (recorder != nullptr) {
      const auto* device = std::get_if<DeviceSourceConfig>(&sensor.source);
      options.can_tap =
          &recorder->add_can_stream({sensor.name, device != nullptr ? device->interface : ""});
    }
    return std::make_unique<LiveImu<imu::CanImuSource>>(
        sensor, "can", devices::open_can_imu_source(sensor, config, options));
  }
  if (sensor.driver == Driver::serial_imu) {
    if (recorder != nullptr) {
      options.serial_tap = &recorder->add_serial_stream({sensor.name, devices::kSerialChunkBytes});
    }
    return std::make_unique<LiveImu<imu::SerialImuSource>>(
        sensor, "serial", devices::open_serial_imu_source(sensor, config, options));
  }
  throw Error("sensor '" + sensor.name + "': driver " + std::string(enum_name(sensor.driver)) +
              " is not a live IMU (can_imu, serial_imu)");
}

}  // namespace livod::daemon::runtime
