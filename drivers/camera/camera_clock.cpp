#include "drivers/camera/camera_clock.hpp"

#include <time.h>

#include <limits>

namespace livod::camera {
namespace {

constexpr std::int64_t kTaiRefreshNs = 1'000'000'000;

std::int64_t read_ns(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

Nanoseconds tai_to_monotonic_offset() {
  std::int64_t best_width = std::numeric_limits<std::int64_t>::max();
  std::int64_t best = 0;
  for (int i = 0; i < 5; ++i) {
    const std::int64_t m0 = read_ns(CLOCK_MONOTONIC);
    const std::int64_t tai = read_ns(CLOCK_TAI);
    const std::int64_t m1 = read_ns(CLOCK_MONOTONIC);
    if (m1 - m0 < best_width) {
      best_width = m1 - m0;
      best = tai - (m0 + (m1 - m0) / 2);
    }
  }
  return Nanoseconds(best);
}

CameraClock::CameraClock(CameraClockConfig config) : config_(config) {}

void CameraClock::map(CameraFrame& frame) {
  const FrameInfo& info = frame.info;
  if (!domain_) {
    ClockDomainConfig d = config_.domain;
    if (config_.mode) {
      d.mode = *config_.mode;
    } else {
      d.mode = info.clock == CameraClockKind::kDevice ? ClockMode::free_running : ClockMode::direct;
    }
    if (d.mode == ClockMode::direct) {
      d.direct_offset =
          info.clock == CameraClockKind::kPtp ? -tai_to_monotonic_offset() : Nanoseconds(0);
    }
    domain_.emplace(d);
    kind_ = info.clock;
    last_tai_refresh_ns_ = info.host_rx.ns;
  }
  if (kind_ == CameraClockKind::kPtp && domain_->config().mode == ClockMode::direct &&
      info.host_rx.ns - last_tai_refresh_ns_ > kTaiRefreshNs) {
    domain_->set_direct_offset(-tai_to_monotonic_offset());
    last_tai_refresh_ns_ = info.host_rx.ns;
  }
  const Nanoseconds before_stamp = info.instant == StampInstant::kStartOfExposure
                                       ? Nanoseconds(0)
                                       : config_.readout + info.exposure;
  const SensorTime start = info.sensor_time - before_stamp;
  const MappedTime mapped_start =
      domain_->observe(start, info.host_rx, info.exposure + config_.readout) + config_.time_offset;
  frame.stamp.sensor = info.sensor_time;
  frame.stamp.host = info.host_rx;
  frame.stamp.mapped = mapped_start + before_stamp;
  frame.exposure_start = mapped_start;
  frame.mid_exposure = mapped_start + info.exposure / 2;
}

std::optional<ClockDomainStats> CameraClock::stats() const {
  if (!domain_) return std::nullopt;
  return domain_->stats();
}

}  // namespace livod::camera
