// candump logs of CAN IMUs: one event per CAN frame, stamped with its log time.

#include <fmt/core.h>

#include <algorithm>

#include "core/error.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "io/candump.hpp"

namespace livod::daemon::replay {
namespace {

class SbgCandumpSource final : public ReplaySource {
 public:
  SbgCandumpSource(const std::filesystem::path& file, const SbgCanIds& ids)
      : reader_(file, {.lenient = true}), decoder_(imu::SbgCanIds{ids.info, ids.accel, ids.gyro}) {}

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
    if (frame_.error || frame_.rtr || frame_.fd) {
      ++ignored_;
      return;
    }
    imu::CanPayload payload;
    payload.id = frame_.id;
    payload.len = frame_.len;
    std::copy_n(frame_.data.begin(), std::min<std::size_t>(frame_.len, payload.data.size()),
                payload.data.begin());
    payload.rx_time_ns = frame_.time_ns;
    if (const auto sample = decoder_.on_frame(payload); sample && sinks.on_imu) {
      sinks.on_imu(sample->imu);
    }
  }

  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  // Lines that do not parse are skipped (read past) and reported as lost.
  [[nodiscard]] io::InputLossLog input_losses() const override { return reader_.losses(); }

  [[nodiscard]] std::string summary() const override {
    const auto& c = decoder_.counters();
    return fmt::format(
        "candump: lines {}, frames {}, error/remote/FD frames ignored {}; SBG: frames {}, samples "
        "{}, malformed {}, incomplete {}, counter wraps {}",
        reader_.stats().lines, reader_.stats().frames, ignored_, c.frames, c.samples, c.malformed,
        c.incomplete, c.counter_wraps);
  }

 private:
  io::CandumpReader reader_;
  imu::SbgCanDecoder decoder_;
  io::CanFrame frame_;
  bool have_frame_ = false;
  bool ended_ = false;
  std::uint64_t ignored_ = 0;
};

}  // namespace

std::unique_ptr<ReplaySource> make_candump_source(const std::filesystem::path& file,
                                                  const CanConfig& can, const std::string& sensor) {
  if (can.decoder != CanDecoder::sbg) {
    throw Error("sensor '" + sensor + "': replaying the " + std::string(enum_name(can.decoder)) +
                " CAN decoder is not supported yet (can.decoder: sbg is)");
  }
  return std::make_unique<SbgCandumpSource>(file, can.sbg_ids);
}

}  // namespace livod::daemon::replay
