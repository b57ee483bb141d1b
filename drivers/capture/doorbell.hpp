#pragma once
// livod::drivers::capture::Doorbell - how producers (capture threads, the scheduler) wake a
// consumer thread that sleeps because its rings are empty, without ever blocking the producer and
// without a system call while the consumer is busy.
//
//   consumer:  token = prepare();  if (nothing queued) wait(token, timeout);
//   producer:  push into the ring;  ring();
//
// ring() bumps a sequence number and issues FUTEX_WAKE only when a consumer announced that it
// sleeps. wait() announces itself, re-checks the sequence and sleeps in FUTEX_WAIT only if nothing
// was rung since prepare() (the kernel re-checks the value atomically). The announcement and the
// re-check (consumer) and the bump and the check (producer) are sequentially consistent, so either
// the producer sees the sleeper and wakes it or the consumer sees the new sequence and does not
// sleep: a ring is never lost. The data itself travels through the SPSC rings (acquire/release);
// the doorbell carries no data. Several producers may ring one doorbell.

#include <atomic>
#include <cstdint>

#include "core/time.hpp"

namespace livod::drivers::capture {

class Doorbell {
 public:
  // Any thread, never blocks (one atomic increment, one load; FUTEX_WAKE if someone sleeps).
  void ring() noexcept;
  // Consumer: the token to pass to wait() after checking for work.
  [[nodiscard]] std::uint32_t prepare() const noexcept {
    return sequence_.load(std::memory_order_seq_cst);
  }
  // Consumer: sleeps until ring() is called after prepare() returned `token`, or for `timeout`
  // (spurious wake-ups possible). Returns at once if it was rung meanwhile.
  void wait(std::uint32_t token, Nanoseconds timeout) noexcept;

  [[nodiscard]] std::uint64_t wakes() const noexcept {
    return wakes_.load(std::memory_order_relaxed);
  }

 private:
  std::atomic<std::uint32_t> sequence_{0};
  std::atomic<std::uint32_t> sleepers_{0};
  std::atomic<std::uint64_t> wakes_{0};  // FUTEX_WAKE calls (for tests and benchmarks)
};

}  // namespace livod::drivers::capture
