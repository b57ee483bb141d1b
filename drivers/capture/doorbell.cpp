#include "drivers/capture/doorbell.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <climits>

namespace livod::drivers::capture {
namespace {

// std::atomic<std::uint32_t> is a plain 32-bit word on Linux (lock-free, standard layout): the
// futex works on its address.
std::uint32_t* word(std::atomic<std::uint32_t>& a) {
  static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t));
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
  return reinterpret_cast<std::uint32_t*>(&a);
}

}  // namespace

void Doorbell::ring() noexcept {
  sequence_.fetch_add(1, std::memory_order_seq_cst);
  if (sleepers_.load(std::memory_order_seq_cst) != 0) {
    wakes_.fetch_add(1, std::memory_order_relaxed);
    ::syscall(SYS_futex, word(sequence_), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr, nullptr, 0);
  }
}

void Doorbell::wait(std::uint32_t token, Nanoseconds timeout) noexcept {
  if (timeout.count() <= 0) return;
  sleepers_.fetch_add(1, std::memory_order_seq_cst);
  if (sequence_.load(std::memory_order_seq_cst) == token) {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(timeout.count() / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(timeout.count() % 1'000'000'000);
    ::syscall(SYS_futex, word(sequence_), FUTEX_WAIT_PRIVATE, token, &ts, nullptr, 0);
  }
  sleepers_.fetch_sub(1, std::memory_order_seq_cst);
}

}  // namespace livod::drivers::capture
