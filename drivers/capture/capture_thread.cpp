#include "drivers/capture/capture_thread.hpp"

#include <pthread.h>
#include <sched.h>

#include <cerrno>
#include <utility>

#include "core/single_writer_counter.hpp"

namespace livod::drivers::capture {

const char* to_string(SchedulingResult r) {
  switch (r) {
    case SchedulingResult::kNotRequested:
      return "not requested";
    case SchedulingResult::kPending:
      return "pending";
    case SchedulingResult::kApplied:
      return "applied";
    case SchedulingResult::kDenied:
      return "denied";
  }
  return "?";
}

CaptureThread::CaptureThread(io::UdpSocket socket, PacketRing& ring, CaptureThreadConfig config)
    : socket_(std::move(socket)),
      ring_(ring),
      config_(std::move(config)),
      local_port_(socket_.local_port()),
      reported_port_(config_.reported_port != 0 ? config_.reported_port : local_port_),
      receive_buffer_bytes_(socket_.effective_receive_buffer_bytes()) {
  if (config_.realtime_priority) published_.priority.store(SchedulingResult::kPending);
  if (config_.cpu) published_.affinity.store(SchedulingResult::kPending);
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

CaptureThread::~CaptureThread() {
  stop();
}

void CaptureThread::stop() {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
}

void CaptureThread::apply_scheduling() {
  const pthread_t self = pthread_self();
  if (!config_.thread_name.empty()) {
    // The kernel limit is 16 bytes with the terminator; a longer name is refused, so cut it.
    const std::string name = config_.thread_name.substr(0, 15);
    pthread_setname_np(self, name.c_str());
  }
  if (config_.cpu) {
    const int cpu = *config_.cpu;
    int rc = EINVAL;  // a CPU number cpu_set_t cannot hold
    if (cpu >= 0 && cpu < CPU_SETSIZE) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(static_cast<std::size_t>(cpu), &set);
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

void CaptureThread::run(const std::stop_token& stop) {
  apply_scheduling();
  std::uint64_t pushed = 0;
  std::uint64_t wakeups = 0;
  std::int64_t last_rx_ns = 0;
  while (!stop.stop_requested()) {
    const auto batch = socket_.receive_batch(config_.poll_timeout_ms);
    const std::uint64_t pushed_before = pushed;
    for (const io::ReceivedDatagram& d : batch) {
      if (ring_.try_push(d.payload, d.rx, reported_port_, d.truncated, d.src_ip, d.src_port)) {
        ++pushed;
      }
      if (config_.tap != nullptr) {
        config_.tap->try_push(d.payload, d.rx, reported_port_, d.truncated, d.src_ip, d.src_port);
      }
      last_rx_ns = d.rx.ns;
    }
    if (pushed != pushed_before && config_.doorbell != nullptr) config_.doorbell->ring();
    ++wakeups;
    // One publication per batch (relaxed: the counters carry no data; the ring publishes the
    // packets itself).
    const io::UdpSocketCounters& c = socket_.counters();
    publish(published_.bytes, c.bytes);
    publish(published_.kernel_drops, c.kernel_drops);
    publish(published_.truncated, c.truncated);
    publish(published_.receive_errors, c.receive_errors);
    publish(published_.missing_timestamps, c.missing_timestamps);
    publish(published_.pushed, pushed);
    publish(published_.last_rx_ns, last_rx_ns);
    publish(published_.datagrams, c.datagrams);
    publish(published_.wakeups, wakeups);
  }
}

CaptureCounters CaptureThread::counters() const {
  CaptureCounters c;
  const auto get = [](const auto& a) { return a.load(std::memory_order_relaxed); };
  c.datagrams = get(published_.datagrams);
  c.bytes = get(published_.bytes);
  c.pushed = get(published_.pushed);
  c.ring_overruns = ring_.overruns();
  c.kernel_drops = get(published_.kernel_drops);
  c.truncated = get(published_.truncated);
  c.receive_errors = get(published_.receive_errors);
  c.missing_timestamps = get(published_.missing_timestamps);
  c.wakeups = get(published_.wakeups);
  c.last_rx_ns = get(published_.last_rx_ns);
  c.priority = get(published_.priority);
  c.affinity = get(published_.affinity);
  c.priority_error = get(published_.priority_error);
  c.affinity_error = get(published_.affinity_error);
  return c;
}

}  // namespace livod::drivers::capture
