// Serial captures of serial / USB IMUs (io/serial_capture.hpp): one event per recorded read,
// stamped with its receive time, decoded by the same stream decoder as the live serial source
// (daemon/devices/imu_decoders.hpp), so a message torn across reads decodes as it did live.

#include <fmt/core.h>

#include "daemon/devices/imu_decoders.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "io/serial_capture.hpp"

namespace livod::daemon::replay {
namespace {

class SerialCaptureSource final : public ReplaySource {
 public:
  SerialCaptureSource(const std::filesystem::path& file,
                      std::unique_ptr<imu::StreamImuDecoder> decoder)
      : reader_(file), decoder_(std::move(decoder)) {}

  std::optional<std::int64_t> peek_time() override {
    if (!have_chunk_ && !ended_) {
      have_chunk_ = reader_.next(chunk_);
      ended_ = !have_chunk_;
    }
    if (!have_chunk_) return std::nullopt;
    return chunk_.rx_time_ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    if (!have_chunk_) return;
    have_chunk_ = false;
    decoder_->on_bytes(chunk_.bytes, chunk_.rx_time_ns, [&](const ImuSample& s) {
      if (sinks.on_imu) sinks.on_imu(s);
    });
  }

  // A message cut by the end of the capture is incomplete: nothing to emit.
  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  [[nodiscard]] std::string summary() const override {
    return fmt::format("serial capture: reads {}, bytes {}; {}: {}", reader_.chunks(),
                       reader_.bytes(), decoder_->model_name(),
                       imu::format_counters(decoder_->counters()));
  }

 private:
  io::SerialCaptureReader reader_;
  std::unique_ptr<imu::StreamImuDecoder> decoder_;
  io::SerialChunk chunk_;
  bool have_chunk_ = false;
  bool ended_ = false;
};

}  // namespace

std::unique_ptr<ReplaySource> make_serial_capture_source(const std::filesystem::path& file,
                                                         const SerialConfig& serial,
                                                         const std::string& sensor) {
  return std::make_unique<SerialCaptureSource>(file,
                                               devices::make_serial_imu_decoder(serial, sensor));
}

}  // namespace livod::daemon::replay
