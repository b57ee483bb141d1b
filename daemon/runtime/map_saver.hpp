#pragma once
// Writes map snapshots as binary PCD files on its own thread (`livod-mapsave`), on the IO side of
// the daemon: the scheduler never takes part in a save (docs/deploy.md "Saving the map").
//
// Why a thread of its own rather than the publisher thread itself: writing and fsyncing 2 M points
// (24 MB) takes from tens of milliseconds to seconds on a robot's eMMC; on the publisher thread it
// would hold back poses and health for that long and could starve its heartbeat into a watchdog
// restart. The publisher thread only hands over a snapshot (a pointer and a count, see
// MapAccumulator::reserve_budget) and later collects the outcome.
//
// Files: DIRECTORY/map-<UTC yyyymmddThhmmssZ of the snapshot>-<save number, 4 digits>.pcd, a new
// file per save (a name that exists already gets "-2", "-3"... appended), or DIRECTORY/map.pcd
// replaced by each save with `overwrite`. Each file is written as NAME.partial, fsynced, renamed
// to NAME and the folder fsynced: a file under its final name is always whole, also after a power
// loss; a failed save removes its partial file.
//
// Threading: start(), busy(), take_result() and wait() from one thread (the publisher thread).

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace livod::daemon::runtime {

struct MapSaverOptions {
  std::filesystem::path directory;  // made absolute at construction
  bool create_directory = false;    // create it (one level) at the first save: the default folder
  bool overwrite = false;           // DIRECTORY/map.pcd replaced by each save
  // Tests: called on the writer thread before each write (a test blocks in it to keep a save in
  // progress). Empty: none.
  std::function<void()> before_write;
};

struct MapSaveOutcome {
  bool ok = false;
  std::filesystem::path path;  // the final file (empty when the save failed)
  std::size_t points = 0;
  std::uint64_t bytes = 0;
  int save_number = 0;                // from 1 in this run
  std::int64_t snapshot_unix_ns = 0;  // when the map was snapshot
  double duration_s = 0.0;            // writing, fsync and rename
  std::string error;                  // why it failed
};

class MapSaver {
 public:
  // `on_done` is called on the writer thread when a save has ended (the publisher rings its
  // doorbell in it); may be empty.
  MapSaver(MapSaverOptions options, std::function<void()> on_done);
  ~MapSaver();  // waits for a running save
  MapSaver(const MapSaver&) = delete;
  MapSaver& operator=(const MapSaver&) = delete;

  // Starts writing `points` x y z float32 points at `xyz` as the next save. The memory must stay
  // valid and unchanged until the outcome is taken (take_result / wait). Returns false, starting
  // nothing, while a save is running or its outcome has not been taken.
  bool start(const float* xyz, std::size_t points, std::int64_t snapshot_unix_ns);
  // A save started whose outcome has not been taken yet.
  [[nodiscard]] bool busy() const;
  // The outcome of the save once it ended (once), else nullopt.
  std::optional<MapSaveOutcome> take_result();
  // Blocks until the running save ends and returns its outcome (nullopt when none is pending).
  std::optional<MapSaveOutcome> wait();

  [[nodiscard]] const std::filesystem::path& directory() const { return options_.directory; }

 private:
  void run(const std::stop_token& stop);
  MapSaveOutcome write(const float* xyz, std::size_t points, std::int64_t snapshot_unix_ns,
                       int number);

  MapSaverOptions options_;
  std::function<void()> on_done_;
  int next_number_ = 1;   // publisher thread
  bool pending_ = false;  // publisher thread: started, outcome not taken

  mutable std::mutex mutex_;
  std::condition_variable_any cv_;
  struct Job {
    const float* xyz = nullptr;
    std::size_t points = 0;
    std::int64_t snapshot_unix_ns = 0;
    int number = 0;
  };
  std::optional<Job> job_;                // guarded by mutex_
  std::optional<MapSaveOutcome> result_;  // guarded by mutex_
  std::jthread thread_;                   // started at the first save; last member
};

// The file name of save `number` of a snapshot taken at `snapshot_unix_ns` (without overwrite):
// map-20261126T061105Z-0001.pcd.
std::string map_file_name(std::int64_t snapshot_unix_ns, int number);

}  // namespace livod::daemon::runtime
