#pragma once
// Map saves while the daemon runs (docs/deploy.md "Saving the map"): on SIGUSR1, on an LCM
// command (livod.command_t COMMAND_SAVE_MAP) and at stop. Lives on the publisher (IO) thread,
// which owns the map (the accumulator of the registered scans the scheduler hands over with every
// frame record) and the LCM bus:
//
//   main thread: SIGUSR1 ─▶ request_from_signal() (an atomic counter, the publisher's doorbell)
//   publisher thread, every turn: turn() ─▶ LCM commands, signal requests ─▶ snapshot (pointer +
//     count of the append-only accumulator) ─▶ MapSaver's writer thread ─▶ outcome ─▶ answers
//
// The scheduler takes no part: its frame time is the same whether a save runs or not (apart from
// sharing the CPUs with the writer; bench/map_save_bench.sh measures it).
//
// Coalescing: one save runs at a time. Requests that arrive while it runs join it: they are
// answered with its file (coalesced = true), which holds the map as of its snapshot. Nothing is
// queued beyond the requests waiting for the running save's answer.
//
// Every outcome is logged and published on LIVOD_COMMAND_RESULT (requested_by "SIGUSR1", "stop"
// or the command's sender).

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "daemon/publish/command_records.hpp"
#include "daemon/runtime/map_saver.hpp"

namespace livod::drivers::capture {
class Doorbell;
}
namespace livod::daemon::replay {
class MapAccumulator;
}

namespace livod::daemon::runtime {

class MessageBus;

struct MapSaveServiceOptions {
  bool enabled = false;  // off: requests are rejected (and logged)
  bool at_stop = false;  // a save when the daemon stops
  MapSaverOptions saver;
};

struct MapSaveStats {
  std::uint64_t requests = 0;   // signals and commands asking for a save
  std::uint64_t saved = 0;      // saves written
  std::uint64_t failed = 0;     // saves that failed
  std::uint64_t coalesced = 0;  // requests answered by a save already running
  std::uint64_t rejected = 0;   // commands not carried out (unknown, disabled)
};

class MapSaveService {
 public:
  // `wake` (the publisher's doorbell) is rung when a signal asks for a save and when a save ends.
  MapSaveService(MapSaveServiceOptions options, drivers::capture::Doorbell& wake);

  // Any thread (the main thread on SIGUSR1): a save, taken at the publisher's next turn.
  void request_from_signal();

  // Publisher thread, every turn: takes the bus's commands and the signals' requests, answers the
  // finished save, starts a save from `map` (may be null: no map is accumulated) when asked.
  // `map` must stay alive and only be appended to while a save runs.
  void turn(const replay::MapAccumulator* map, MessageBus* bus);
  // Publisher thread, at stop (after the last turn): answers the running save, then saves once
  // more if at_stop (and waits for it).
  void finish(const replay::MapAccumulator* map, MessageBus* bus);

  [[nodiscard]] const MapSaveStats& stats() const { return stats_; }
  [[nodiscard]] bool enabled() const { return options_.enabled; }

 private:
  struct Waiting {
    std::int64_t request_id = 0;
    std::string requested_by;
    bool coalesced = false;
  };
  void take_requests(MessageBus* bus);
  void start_or_join(const replay::MapAccumulator* map, MessageBus* bus);
  void answer(const MapSaveOutcome& outcome, MessageBus* bus);
  void reply(MessageBus* bus, publish::CommandResultRecord result);

  MapSaveServiceOptions options_;
  drivers::capture::Doorbell& wake_;
  std::atomic<std::uint64_t> signals_{0};  // SIGUSR1 requests so far (main thread increments)
  std::uint64_t signals_taken_ = 0;
  std::vector<publish::CommandRecord> commands_;  // reused buffer
  std::vector<Waiting> new_requests_;             // this turn's
  std::vector<Waiting> joined_;                   // answered by the running save
  std::uint64_t malformed_logged_ = 0;
  MapSaveStats stats_;
  MapSaver saver_;  // last: its writer thread ends before the rest goes
};

// Where saves go: the configured folder, else OUT_DIR/maps (`replay --realtime -o OUT_DIR`), else
// $STATE_DIRECTORY/maps (systemd's StateDirectory=; its first entry), else ./maps. A default folder
// is created at the first save; a configured one must exist.
MapSaverOptions map_saver_options(const std::filesystem::path& configured,
                                  const std::filesystem::path& out_dir,
                                  const char* state_directory_env, bool overwrite);

}  // namespace livod::daemon::runtime
