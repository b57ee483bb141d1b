#pragma once
// The filter update's own thread (`livod run`): the scheduler thread hands it one estimator group
// at a time and, while the update runs, keeps draining the rings and publishing IMU-rate poses, so
// that a 20 ms scan update does not delay the IMU-rate pose by 20 ms. Ownership is handed over,
// never shared: between start() and collect() the job owns the estimator and the scheduler thread
// touches nothing of it (it queues what arrives meanwhile, scheduler.hpp).
//
//   scheduler thread:  start();  ... poll done() between ring events ...;  collect();
//   update thread:     runs the job, marks it done, rings the scheduler's doorbell.
//
// The job is fixed at construction (nothing is allocated per frame). The thread advances its
// heartbeat on every idle wake-up (every `idle_beat`) and after every job, so that health and the
// systemd watchdog tell an idle update thread from one stuck in an update.

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <stop_token>
#include <thread>

#include "core/time.hpp"
#include "daemon/runtime/heartbeat.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::daemon::runtime {

struct UpdateThreadOptions {
  std::optional<int> priority;  // SCHED_FIFO (realtime.scheduler_priority); refusal is logged
  std::optional<int> cpu;       // affinity (realtime.scheduler_cpu)
  Nanoseconds idle_beat{100'000'000};
};

class UpdateThread {
 public:
  // `done_bell` (may be null) is rung when a job ends.
  UpdateThread(std::function<void()> job, drivers::capture::Doorbell* done_bell,
               UpdateThreadOptions options = {});
  // Stops the thread; a running job is finished first.
  ~UpdateThread();
  UpdateThread(const UpdateThread&) = delete;
  UpdateThread& operator=(const UpdateThread&) = delete;

  // Scheduler thread: runs the job once. Not while busy().
  void start();
  // Scheduler thread: started and not yet collected.
  [[nodiscard]] bool busy() const { return busy_; }
  // Scheduler thread: the started job has ended (its effects are visible after this returns true).
  [[nodiscard]] bool done() const { return done_.load(std::memory_order_acquire); }
  // Scheduler thread, after done(): idle again; rethrows what the job threw.
  void collect();
  // Scheduler thread: waits for the started job to end, then collect(). No-op when not busy().
  void wait_and_collect();

  [[nodiscard]] std::uint64_t beats() const { return beat_.beats(); }
  [[nodiscard]] std::uint64_t jobs() const { return jobs_.load(std::memory_order_relaxed); }

 private:
  void loop(const std::stop_token& stop);

  std::function<void()> job_;
  drivers::capture::Doorbell* done_bell_;
  UpdateThreadOptions options_;
  std::mutex mutex_;
  std::condition_variable_any cv_;
  bool requested_ = false;  // under mutex_
  bool busy_ = false;       // scheduler thread only
  std::atomic<bool> done_{false};
  std::exception_ptr error_;  // written by the job's thread before done_ (release)
  Heartbeat beat_;
  std::atomic<std::uint64_t> jobs_{0};
  std::jthread thread_;  // last: started once everything above exists
};

}  // namespace livod::daemon::runtime
