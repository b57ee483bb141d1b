#pragma once
// A fixed set of worker threads that run the estimator's parallel work (estimator::TaskRunner):
// residual rows and map refits on every core, the way FAST-LIVO2 uses OpenMP, but started once
// instead of per call and owned by the daemon (the estimator never sees a thread).
//
// run() hands out task indices through one atomic counter; the calling thread works too, so a
// pool of N threads starts N - 1 workers. Between calls the workers sleep on a condition
// variable: no spinning on a shared robot computer.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "estimator/task_runner.hpp"

namespace livod::daemon {

class WorkerPool final : public estimator::TaskRunner {
 public:
  // `threads` counts the caller: 2 starts one worker. <= 1 runs everything on the caller.
  // `on_worker_start` (may be empty) runs first on each worker thread (the daemon gives the
  // workers the update thread's real-time priority there).
  explicit WorkerPool(int threads, const std::function<void()>& on_worker_start = {});
  ~WorkerPool() override;

  void run(std::size_t count, const std::function<void(std::size_t)>& task) override;
  [[nodiscard]] int concurrency() const override { return static_cast<int>(workers_.size()) + 1; }

  // Threads to use when the configuration says 0 ("all cores").
  [[nodiscard]] static int hardware_threads();

 private:
  void worker_loop();
  // Takes and runs tasks of the current call until none is left.
  void drain();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;  // a call started, or stop
  std::condition_variable idle_;  // a worker left drain()
  // The current call; written under mutex_ while no worker is draining.
  const std::function<void(std::size_t)>* task_ = nullptr;
  std::size_t count_ = 0;
  std::uint64_t generation_ = 0;
  int active_ = 0;  // workers inside drain()
  bool stop_ = false;
  std::atomic<std::size_t> next_{0};
};

}  // namespace livod::daemon
