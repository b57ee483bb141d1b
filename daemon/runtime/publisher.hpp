#pragma once
// The publisher/IO thread (DESIGN.md "Data flow"): everything that may block or take time away
// from the scheduler happens here - LCM publishing, the trajectory file, the map accumulated for
// map.pcd, the timing report, log lines. It sleeps on the channels' doorbell, takes the records
// the scheduler published (live_outputs.hpp) and gives them back.
//
// Latency is measured here, after each publish: from the host receive time of the packet that
// completed a scan (or of the IMU packet) to the moment its pose left the process.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>

#include "core/realtime_offset.hpp"
#include "daemon/publish/command_records.hpp"
#include "daemon/replay/map_accumulator.hpp"
#include "daemon/replay/trajectory_writer.hpp"
#include "daemon/runtime/heartbeat.hpp"
#include "daemon/runtime/latency_histogram.hpp"
#include "daemon/runtime/live_outputs.hpp"
#include "daemon/runtime/map_save_service.hpp"
#include "daemon/runtime/records.hpp"

namespace livod::daemon::runtime {

// Where poses, health and clouds go (LCM in the daemon: lcm_bus.hpp). Called on the publisher
// thread only.
class MessageBus {
 public:
  virtual ~MessageBus() = default;
  // Filter poses and IMU-rate poses (PoseRecord::source tells them apart).
  virtual void publish_pose(const PoseRecord& pose) = 0;
  virtual void publish_health(const HealthRecord& health) = 0;
  // The registered scan (decimated) of a frame.
  virtual void publish_cloud(const publish::CloudRecord& cloud) = 0;
  // unix = mapped + offset, refreshed by the publisher at every health record.
  virtual void set_time_base(publish::TimeBase /*time_base*/) {}
  // Per-channel counters for health (empty when the bus has none).
  [[nodiscard]] virtual std::vector<publish::ChannelCounters> channel_counters() const {
    return {};
  }
  // Messages that could not be sent.
  [[nodiscard]] virtual std::uint64_t failures() const = 0;
  // Requests received since the previous call (LCM: livod.command_t), appended to `out`; and
  // their answers (map_save_service.hpp). Default: a bus without commands.
  virtual void poll_commands(std::vector<publish::CommandRecord>& /*out*/) {}
  virtual void publish_command_result(const publish::CommandResultRecord& /*result*/) {}
  // Messages on the command channel that were not commands (dropped).
  [[nodiscard]] virtual std::uint64_t malformed_commands() const { return 0; }
};

struct PublisherOptions {
  std::filesystem::path trajectory;     // TUM, one line per frame; empty: none
  std::filesystem::path map_pcd;        // written at stop; empty: none
  MapSaveServiceOptions map_saves;      // saves on request while running (map_save_service.hpp)
  std::filesystem::path timing_report;  // written at stop; empty: none
  double map_cell_m = 0.2;
  std::size_t map_max_points = 2'000'000;
  bool publish_cloud = false;
  Nanoseconds stuck_after{2'000'000'000};  // a heartbeat older than this is "stuck" in health
  // Log one health summary line this often (state changes are logged at once).
  Nanoseconds log_period{60'000'000'000};
  // Called on the publisher thread with each health record once it is complete (the daemon
  // derives the systemd STATUS= line from it); may be empty.
  std::function<void(const HealthRecord&)> on_health;
  // SCHED_FIFO priority and CPU of the publisher thread (a refusal is logged): it is the last hop
  // of the IMU-rate pose, which must not wait behind other processes for a core.
  std::optional<int> priority;
  std::optional<int> cpu;
};

struct PublisherStats {
  std::uint64_t poses = 0;
  std::uint64_t imu_poses = 0;
  std::uint64_t health = 0;
  std::uint64_t stale_poses = 0;
  LatencyHistogram pose_latency_ms;
  LatencyHistogram imu_latency_ms;
  LatencyHistogram frame_ms;
  LatencyHistogram frame_cpu_ms;
  MapSaveStats map_saves;
};

class Publisher {
 public:
  // `bus` may be null (no messages: files only); it and `channels` must outlive the publisher.
  // Opens the trajectory file at once (livod::Error if it cannot be created).
  Publisher(PublisherChannels& channels, MessageBus* bus, PublisherOptions options);
  ~Publisher();
  Publisher(const Publisher&) = delete;
  Publisher& operator=(const Publisher&) = delete;

  // Threads whose heartbeats health reports (call before start()).
  void watch(std::string name, std::function<std::uint64_t()> beats);
  void start();
  // Any thread (the main thread on SIGUSR1): save the map now (map_save_service.hpp).
  void request_map_save() { map_saves_.request_from_signal(); }
  // Drains every channel, writes the map and the timing report, joins. Call once the producer
  // (the scheduler) has stopped. Idempotent. Returns the errors met while writing (empty: none).
  std::vector<std::string> stop();

  [[nodiscard]] const Heartbeat& heartbeat() const { return heartbeat_; }
  // After stop().
  [[nodiscard]] const PublisherStats& stats() const { return stats_; }
  [[nodiscard]] std::size_t map_points() const { return map_ ? map_->size() : 0; }
  [[nodiscard]] const replay::MapAccumulator* map() const { return map_ ? &*map_ : nullptr; }

 private:
  void run(const std::stop_token& stop);
  // Takes everything queued; returns whether anything was.
  bool drain();
  // Publishes the queued IMU-rate poses; also called between slices of a frame's longer work.
  bool publish_imu_poses();
  // Publishes the filter poses sent ahead of their frames (LiveOutputs::on_estimate).
  bool publish_estimates();
  void on_frame(FrameRecord& f);
  void on_health(HealthRecord& h);
  void log_health(const HealthRecord& h);

  PublisherChannels& channels_;
  MessageBus* bus_;
  PublisherOptions options_;
  Heartbeat heartbeat_;
  HeartbeatMonitor threads_;
  std::optional<replay::TrajectoryWriter> trajectory_;
  std::optional<replay::MapAccumulator> map_;
  PublisherStats stats_;
  LatencyHistogram window_pose_latency_;  // since the previous health record
  LatencyHistogram window_imu_latency_;
  std::optional<HostTime> last_log_;
  std::string last_states_;     // sensor states + estimator status of the last logged health
  publish::CloudRecord cloud_;  // reused for every frame (its vector keeps its capacity)
  RealtimeToMonotonic realtime_;
  std::vector<std::string> errors_;
  bool stopped_ = false;
  MapSaveService map_saves_;  // after map_: a running save reads it
  std::jthread thread_;       // last
};

}  // namespace livod::daemon::runtime
