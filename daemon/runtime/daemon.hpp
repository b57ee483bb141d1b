#pragma once
// `livod run` (live sensors) and `livod replay --realtime` (recordings at their recorded pace):
// the threads of DESIGN.md "Data flow" around the scheduler loop.
//
//   capture threads (one per socket; or a pacer thread per pcap) ──rings──▶ scheduler thread
//   (sources, clock domains, estimator on the worker pool) ──records──▶ publisher thread (LCM,
//   trajectory, map, timing, log lines); control threads (Livox supervisor, Ouster metadata);
//   the calling thread handles signals (SIGINT/SIGTERM stop; SIGHUP is ignored: no reload; SIGUSR1
//   saves the map, on the IO side: runtime/map_save_service.hpp) and
//   talks to systemd (READY, STATUS, the heartbeat-gated WATCHDOG ping, STOPPING).
//
// Stopping (a signal, the options' stop token, or the end of a paced recording): the sources stop
// capturing, the scheduler drains their rings (bounded in time), flushes the decoders and runs the
// queued scans, publishes a last health record; the publisher drains, writes the map and the
// timing report and closes the trajectory.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <stop_token>
#include <string>
#include <utility>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/runtime/cpu_latency_request.hpp"
#include "daemon/runtime/publisher.hpp"
#include "estimator/pipeline.hpp"
#include "io/input_loss.hpp"

namespace livod::daemon::runtime {

struct DaemonOptions {
  // Recordings paced at their recorded speed instead of live sensors (replay --realtime); the
  // inputs are taken as `livod replay` takes them (NAME=PATH or PATH).
  bool paced_replay = false;
  std::vector<std::string> inputs;
  // Write trajectory.txt, map.pcd and timing.txt here instead of the configuration's outputs.
  std::optional<std::filesystem::path> out_dir;
  // Record the live sensors' raw data into a new subfolder of this folder (`livod run --record`);
  // empty: the configuration's outputs.record (docs/record.md).
  std::filesystem::path record_dir;
  MessageBus* bus = nullptr;  // where poses and health go (LCM); null: nowhere
  int threads = -1;           // estimator threads; < 0: estimator.threads (0 there: one per core)
  std::size_t max_queued_scans = 4;  // the estimator's scan queue (whole scans dropped beyond)
  bool ephemeral_ports = false;      // tests: bind ephemeral ports (see on_ready)
  // Stops the daemon like SIGTERM (tests run it in-process).
  std::stop_token stop;
  // Stops it after this long (replay --realtime --max-duration); 0: never.
  Nanoseconds max_duration{0};
  double map_cell_m = 0.2;                 // map.pcd voxel filter cell
  std::size_t map_max_points = 2'000'000;  // map.pcd point budget
  // Called on the calling thread once every socket is bound and every thread runs: the bound
  // ports per sensor ("os1.lidar" -> 40123).
  std::function<void(const std::vector<std::pair<std::string, std::uint16_t>>&)> on_ready;
  // Speak systemd's notification protocol (service_notifier.hpp) when NOTIFY_SOCKET is set:
  // READY=1, STATUS=, heartbeat-gated WATCHDOG=1, STOPPING=1. `livod run` sets it.
  bool notify_systemd = false;
  // Tests: called on the scheduler thread at the top of every loop turn, before its heartbeat
  // (a test blocks in it to stall the scheduler and see the watchdog pings stop). Empty: none.
  std::function<void()> scheduler_turn_hook;
  // Tests: called on the map writer thread before each map save is written (a test blocks in it
  // to keep a save in progress and see requests coalesce). Empty: none.
  std::function<void()> map_save_hook;
  // The file realtime.cpu_dma_latency_us is written to (tests: a scratch file).
  std::filesystem::path cpu_latency_device = CpuLatencyRequest::kDevice;
};

struct DaemonResult {
  int exit_code = 0;
  std::uint64_t frames = 0;
  PublisherStats publisher;
  std::vector<std::string> sensor_summaries;  // "name: <source summary>"
  std::vector<std::string> errors;            // what went wrong (exit_code != 0) or was lost
  std::string stopped_by;                     // "SIGTERM", "end of recording", ...
  int stop_signal = 0;                        // SIGINT / SIGTERM when one stopped it
  io::InputLossLog losses;  // paced replay: what the recordings' readers could not read
  estimator::PipelineCounters
      estimator;  // scans, IMU samples, images in; image groups, VIO updates
};

// Runs until stopped. The configuration must have loaded without errors. Throws livod::Error
// before any thread starts when a sensor cannot be opened (a port in use, a live source the
// daemon cannot run); errors after that are in the result (exit_code 1).
DaemonResult run_daemon(const LivodConfig& config, const DaemonOptions& options);

}  // namespace livod::daemon::runtime
