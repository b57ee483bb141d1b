#include "daemon/runtime/update_thread.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <utility>

#include "daemon/runtime/thread_scheduling.hpp"

namespace livod::daemon::runtime {

UpdateThread::UpdateThread(std::function<void()> job, drivers::capture::Doorbell* done_bell,
                           UpdateThreadOptions options)
    : job_(std::move(job)),
      done_bell_(done_bell),
      options_(options),
      thread_([this](const std::stop_token& stop) { loop(stop); }) {}

UpdateThread::~UpdateThread() {
  thread_.request_stop();
  if (thread_.joinable()) thread_.join();
}

void UpdateThread::start() {
  busy_ = true;
  done_.store(false, std::memory_order_relaxed);
  {
    const std::lock_guard lock(mutex_);
    requested_ = true;
  }
  cv_.notify_one();
}

void UpdateThread::collect() {
  busy_ = false;
  done_.store(false, std::memory_order_relaxed);
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void UpdateThread::wait_and_collect() {
  if (!busy_) return;
  {
    // The job's end is published through done_ (and the doorbell); waiting here is for shutdown
    // and the end of a replay only, so a short sleep loop is enough.
    while (!done()) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  collect();
}

void UpdateThread::loop(const std::stop_token& stop) {
  if (const auto refused = apply_thread_scheduling("livod-update", options_.priority, options_.cpu);
      !refused.empty()) {
    spdlog::warn("update thread: {}", refused);
  }
  const auto idle = std::chrono::nanoseconds(options_.idle_beat.count());
  std::unique_lock lock(mutex_);
  while (true) {
    beat_.beat();
    cv_.wait_for(lock, stop, idle, [this] { return requested_; });
    if (!requested_) {
      if (stop.stop_requested()) return;
      continue;
    }
    requested_ = false;
    lock.unlock();
    try {
      job_();
    } catch (...) {
      error_ = std::current_exception();
    }
    jobs_.fetch_add(1, std::memory_order_relaxed);
    done_.store(true, std::memory_order_release);
    if (done_bell_ != nullptr) done_bell_->ring();
    lock.lock();
  }
}

}  // namespace livod::daemon::runtime
