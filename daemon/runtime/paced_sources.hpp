#pragma once
// `livod replay --realtime`: recordings released at their recorded pace, against one schedule for
// every sensor (record time t is due at start + (t - t0), t0 the earliest first event of all the
// recordings), through the same path as live operation:
//   pcap     a pacer thread pushes each datagram into the packet ring of its port, stamped with
//            the monotonic time of the push as a capture thread would stamp it; the scheduler
//            drains the rings through a drivers::capture::StreamConsumer, exactly as live;
//   others   (candump logs, bag topics: live has no ring for them yet) the recorded source is
//            released by the scheduler itself when its event is due; its receive times are moved
//            onto the monotonic clock by the same schedule (t -> start + (t - t0)).
// Either way the scheduler, its clock domains and the estimator see what they see live: host
// times on CLOCK_MONOTONIC that advance with the wall clock.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "core/time.hpp"
#include "daemon/config/config.hpp"
#include "daemon/runtime/source.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::daemon::runtime {

// The common schedule of a paced replay.
struct PaceSchedule {
  std::int64_t t0_record_ns = 0;  // the earliest first event of every recording
  HostTime start;                 // when t0 is due (CLOCK_MONOTONIC)
  drivers::capture::Doorbell* doorbell =
      nullptr;  // rung by the pacer threads (wakes the scheduler)

  [[nodiscard]] HostTime due(std::int64_t record_ns) const {
    return start + Nanoseconds(record_ns - t0_record_ns);
  }
};

// A pcap of a packet LiDAR paced into rings (pacer thread) and drained by a StreamConsumer.
// `ports`: the pcap's destination ports to replay (empty: the decoder's default ports). The
// pacer starts at once; call it after the schedule's start is fixed.
std::unique_ptr<MeasurementSource> open_paced_pcap(const SensorConfig& sensor,
                                                   const std::filesystem::path& file,
                                                   const std::vector<std::uint16_t>& ports,
                                                   const PaceSchedule& schedule);

// Any recorded source released at its recorded pace by the scheduler, its receive times moved
// onto the schedule's clock.
std::unique_ptr<MeasurementSource> pace_recording(std::unique_ptr<MeasurementSource> recorded,
                                                  const PaceSchedule& schedule);

}  // namespace livod::daemon::runtime
