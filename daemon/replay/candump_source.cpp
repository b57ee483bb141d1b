// candump logs of CAN IMUs: one event per CAN frame, stamped with its log time, decoded by the
// same decoder as the live SocketCAN source (daemon/devices/imu_decoders.hpp).

#include <fmt/core.h>

#include "daemon/devices/imu_decoders.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "drivers/imu/candump_frames.hpp"
#include "io/candump.hpp"

namespace livod::daemon::replay {
namespace {

class CanCandumpSource final : public ReplaySource {
 public:
  CanCandumpSource(const std::filesystem::path& file, std::unique_ptr<imu::CanImuDecoder> decoder)
      : reader_(file, {.lenient = true}), decoder_(std::move(decoder)) {}

  std::optional<std::int64_t> peek_time() override {
    if (!have_frame_ && !ended_) {
      have_frame_ = reader_.next(frame_);
      ended_ = !have_frame_;
    }
    if (!have_frame_) return std::nullopt;
    return frame_.time_ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    if (!have_frame_) return;
    have_frame_ = false;
    if (frame_.error || frame_.rtr) {
      ++ignored_;
      return;
    }
    decoder_->on_frame(imu::to_can_record(frame_), [&](const ImuSample& s) {
      if (sinks.on_imu) sinks.on_imu(s);
    });
  }

  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  // Lines that do not parse are skipped (read past) and reported as lost.
  [[nodiscard]] io::InputLossLog input_losses() const override { return reader_.losses(); }

  [[nodiscard]] std::string summary() const override {
    return fmt::format("candump: lines {}, frames {}, error/remote frames ignored {}; {}: {}",
                       reader_.stats().lines, reader_.stats().frames, ignored_,
                       decoder_->model_name(), imu::format_counters(decoder_->counters()));
  }

 private:
  io::CandumpReader reader_;
  std::unique_ptr<imu::CanImuDecoder> decoder_;
  io::CanFrame frame_;
  bool have_frame_ = false;
  bool ended_ = false;
  std::uint64_t ignored_ = 0;
};

}  // namespace

std::unique_ptr<ReplaySource> make_candump_source(const std::filesystem::path& file,
                                                  const CanConfig& can, const std::string& sensor) {
  return std::make_unique<CanCandumpSource>(file, devices::make_can_imu_decoder(can, sensor));
}

}  // namespace livod::daemon::replay
