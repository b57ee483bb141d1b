#pragma once
// A packet LiDAR (Velodyne, Ouster, Livox, Hesai) live over UDP, as a runtime source: one capture
// thread per port into a packet ring (drivers/capture/live_source.hpp) whose slots are the
// family's largest datagrams (drivers/lidar_family.hpp), drained by the scheduler through the
// family's decoder (its factory), with the family's supervision beside it:
//   Livox:  livox::LivoxSupervisor (a control thread: handshake/discovery, heartbeats, STALE and
//           re-handshake without touching the data path);
//   Ouster: the metadata file, or HTTP from the sensor (an OusterMetadataFetcher thread) when none
//           is configured or the sensor re-initialises (drivers::ouster::OusterReinitHandler swaps
//           the decoder between deliveries);
//   Velodyne, Hesai: nothing to supervise (a silent sensor is STALE and streams again by itself).
//
// Every socket is bound by the constructor (errors name the sensor and the address), so a daemon
// that has built its sources is ready to receive.

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/runtime/source.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::daemon::runtime {

struct LiveOptions {
  std::optional<int> capture_priority;  // SCHED_FIFO priority of the capture threads
  std::optional<int> capture_cpu;       // pin the capture threads to this CPU
  Nanoseconds stale_after{500'000'000};
  // Replaces the configured local ports (tests bind ephemeral ports, reported by local_ports()).
  bool ephemeral_ports = false;
  // Rung by the capture threads when they queue packets (wakes the scheduler). May be null.
  drivers::capture::Doorbell* doorbell = nullptr;
};

class LiveLidarSource : public MeasurementSource {
 public:
  // The UDP ports actually bound, one per stream ("lidar", "imu", "position"), for tests and logs.
  [[nodiscard]] virtual std::vector<std::pair<std::string, std::uint16_t>> local_ports() const = 0;
};

// Opens the sensor's sockets and starts its capture (and control) threads. Throws livod::Error
// naming the sensor for a driver that is not a packet LiDAR, a source that is not UDP, a port
// that cannot be bound or a metadata/calibration file that cannot be read.
std::unique_ptr<LiveLidarSource> open_live_lidar(const SensorConfig& sensor,
                                                 const LiveOptions& options);

}  // namespace livod::daemon::runtime
