#include "daemon/worker_pool.hpp"

#include <algorithm>

namespace livod::daemon {

WorkerPool::WorkerPool(int threads, const std::function<void()>& on_worker_start) {
  const int workers = std::max(0, threads - 1);
  workers_.reserve(static_cast<std::size_t>(workers));
  for (int i = 0; i < workers; ++i) {
    workers_.emplace_back([this, on_worker_start] {
      if (on_worker_start) on_worker_start();
      worker_loop();
    });
  }
}

WorkerPool::~WorkerPool() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& t : workers_) t.join();
}

int WorkerPool::hardware_threads() {
  return static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
}

void WorkerPool::run(std::size_t count, const std::function<void(std::size_t)>& task) {
  if (count == 0) return;
  if (workers_.empty() || count == 1) {
    for (std::size_t i = 0; i < count; ++i) task(i);
    return;
  }
  {
    std::unique_lock<std::mutex> lock(mutex_);
    // A worker that woke late for the previous call may still be in drain() (finding nothing):
    // the call's fields must not change under it.
    idle_.wait(lock, [this] { return active_ == 0; });
    task_ = &task;
    count_ = count;
    next_.store(0, std::memory_order_relaxed);
    ++generation_;
  }
  wake_.notify_all();
  drain();
  std::unique_lock<std::mutex> lock(mutex_);
  // Every task has been taken; wait for those still running on workers.
  idle_.wait(lock, [this] { return active_ == 0; });
}

void WorkerPool::drain() {
  for (;;) {
    const std::size_t i = next_.fetch_add(1, std::memory_order_relaxed);
    if (i >= count_) return;
    (*task_)(i);
  }
}

void WorkerPool::worker_loop() {
  std::uint64_t seen = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
    if (stop_) return;
    seen = generation_;
    ++active_;
    lock.unlock();
    drain();
    lock.lock();
    --active_;
    if (active_ == 0) idle_.notify_all();
  }
}

}  // namespace livod::daemon
