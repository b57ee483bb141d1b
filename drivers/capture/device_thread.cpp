#include "drivers/capture/device_thread.hpp"

#include <pthread.h>
#include <sched.h>

#include <exception>
#include <utility>

#include "core/single_writer_counter.hpp"

namespace livod::drivers::capture {

const char* to_string(DeviceState s) {
  switch (s) {
    case DeviceState::kOpening:
      return "OPENING";
    case DeviceState::kStreaming:
      return "STREAMING";
    case DeviceState::kLost:
      return "LOST";
    case DeviceState::kStopped:
      return "STOPPED";
  }
  return "?";
}

DeviceThread::DeviceThread(DeviceLink& link, DeviceThreadConfig config)
    : link_(link), config_(std::move(config)) {
  if (config_.poll_timeout.count() <= 0) config_.poll_timeout = std::chrono::milliseconds(1);
  if (config_.wait_for_device) {
    try {
      link_.open();
      open_ = true;
    } catch (const std::exception& e) {
      // Not there yet: the thread retries (state OPENING until the first open succeeds).
      publish(published_.open_failures, std::uint64_t{1});
      set_error(e.what());
      first_retry_ns_ = host_now().ns + config_.reopen_interval.count();
    }
  } else {
    link_.open();  // throws: a device missing at start-up is reported to the caller
    open_ = true;
  }
  if (open_) {
    publish(published_.opens, std::uint64_t{1});
    publish(published_.state, DeviceState::kStreaming);
  }
  if (config_.realtime_priority) publish(published_.priority, SchedulingResult::kPending);
  if (config_.cpu) publish(published_.affinity, SchedulingResult::kPending);
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

DeviceThread::~DeviceThread() {
  stop();
}

void DeviceThread::stop() {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
  if (open_ && !closed_) {
    link_.close();
    open_ = false;
  }
  closed_ = true;
  publish(published_.state, DeviceState::kStopped);
}

void DeviceThread::set_error(std::string message) {
  const std::lock_guard lock(error_mutex_);
  last_error_ = std::move(message);
}

std::string DeviceThread::last_error() const {
  const std::lock_guard lock(error_mutex_);
  return last_error_;
}

void DeviceThread::apply_scheduling() {
  const pthread_t self = pthread_self();
  if (!config_.thread_name.empty()) {
    const std::string name = config_.thread_name.substr(0, 15);
    pthread_setname_np(self, name.c_str());
  }
  if (config_.cpu) {
    cpu_set_t set;
    CPU_ZERO(&set);
    int rc = EINVAL;
    if (*config_.cpu >= 0 && *config_.cpu < CPU_SETSIZE) {
      CPU_SET(*config_.cpu, &set);
      rc = pthread_setaffinity_np(self, sizeof(set), &set);
    }
    publish(published_.affinity_error, rc);
    publish(published_.affinity, rc == 0 ? SchedulingResult::kApplied : SchedulingResult::kDenied);
  }
  if (config_.realtime_priority) {
    sched_param param{};
    param.sched_priority = *config_.realtime_priority;
    const int rc = pthread_setschedparam(self, SCHED_FIFO, &param);
    publish(published_.priority_error, rc);
    publish(published_.priority, rc == 0 ? SchedulingResult::kApplied : SchedulingResult::kDenied);
  }
}

void DeviceThread::run(const std::stop_token& stop) {
  apply_scheduling();
  std::uint64_t wakeups = 0;
  std::int64_t last_data_ns = 0;
  std::int64_t streaming_since_ns = host_now().ns;
  std::int64_t next_open_ns = first_retry_ns_;
  const std::int64_t silence_ns = config_.silence_timeout.count();
  // Health shows why a device is not streaming; once data flows after a reopen the reason is
  // history (the loss and failure counters keep it): an operator read a stale error next to
  // STREAMING as a current fault. A reopened device that stays silent keeps its reason.
  bool error_outdated = false;
  while (!stop.stop_requested()) {
    ++wakeups;
    publish(published_.wakeups, wakeups);
    if (!open_) {
      const std::int64_t now = host_now().ns;
      if (now < next_open_ns) {
        // Sleep in poll_timeout steps so that a stop request is seen promptly.
        std::this_thread::sleep_for(std::min<std::chrono::nanoseconds>(
            config_.poll_timeout, std::chrono::nanoseconds(next_open_ns - now)));
        continue;
      }
      try {
        link_.open();
        open_ = true;
        streaming_since_ns = host_now().ns;
        // A late first open (wait_for_device) is not a reconnect.
        if (published_.opens.load(std::memory_order_relaxed) > 0) bump(published_.reconnects);
        bump(published_.opens);
        publish(published_.state, DeviceState::kStreaming);
        error_outdated = true;
      } catch (const std::exception& e) {
        bump(published_.open_failures);
        set_error(e.what());
        next_open_ns = host_now().ns + config_.reopen_interval.count();
      }
      continue;
    }
    DeviceLink::Wait w = link_.wait_and_read(config_.poll_timeout);
    const std::int64_t now = host_now().ns;
    if (w == DeviceLink::Wait::kData) {
      last_data_ns = now;
      publish(published_.last_data_ns, last_data_ns);
      if (error_outdated) {
        set_error({});
        error_outdated = false;
      }
      if (config_.doorbell != nullptr) config_.doorbell->ring();
    }
    if (w != DeviceLink::Wait::kLost && !link_.service()) w = DeviceLink::Wait::kLost;
    std::string reason;
    if (w == DeviceLink::Wait::kLost) {
      reason = link_.loss_reason();
    } else if (silence_ns > 0 && now - std::max(last_data_ns, streaming_since_ns) > silence_ns) {
      reason = link_.describe() + ": no data for " +
               std::to_string(static_cast<double>(silence_ns) * 1e-9) + " s";
    }
    if (!reason.empty()) {
      // Reported before closing: releasing a vanished device can take a while.
      bump(published_.losses);
      publish(published_.state, DeviceState::kLost);
      set_error(std::move(reason));
      link_.close();
      open_ = false;
      next_open_ns = host_now().ns + config_.reopen_interval.count();
    }
  }
}

DeviceThreadCounters DeviceThread::counters() const {
  const auto get = [](const auto& a) { return a.load(std::memory_order_relaxed); };
  DeviceThreadCounters c;
  c.state = get(published_.state);
  c.opens = get(published_.opens);
  c.open_failures = get(published_.open_failures);
  c.losses = get(published_.losses);
  c.reconnects = get(published_.reconnects);
  c.wakeups = get(published_.wakeups);
  c.last_data_ns = get(published_.last_data_ns);
  c.priority = get(published_.priority);
  c.affinity = get(published_.affinity);
  c.priority_error = get(published_.priority_error);
  c.affinity_error = get(published_.affinity_error);
  return c;
}

}  // namespace livod::drivers::capture
