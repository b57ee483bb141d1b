#pragma once
// The signals livod handles itself: SIGINT and SIGTERM (stop cleanly, keeping the work done),
// SIGHUP (no reload: ignored, logged), SIGUSR1. They are blocked and taken with sigtimedwait()
// by the thread that owns the run, never delivered asynchronously: no handler, no global flag.
//
// Block them before any thread starts (threads inherit the mask), so that a process-directed
// signal cannot land in a thread that would take its default action (terminate).

#include <signal.h>

#include "core/time.hpp"

namespace livod::daemon::runtime {

// Blocks the handled signals in the calling thread for its lifetime; restores the previous mask
// when destroyed, after consuming the ones that arrived meanwhile (they were handled).
class BlockedSignals {
 public:
  BlockedSignals();
  ~BlockedSignals();
  BlockedSignals(const BlockedSignals&) = delete;
  BlockedSignals& operator=(const BlockedSignals&) = delete;

  // The next handled signal pending or arriving within `timeout` (0: just look), or 0.
  [[nodiscard]] int wait(Nanoseconds timeout) const;

  // The signal set handled by livod.
  [[nodiscard]] static sigset_t handled();

 private:
  sigset_t set_{};
  sigset_t previous_{};
};

// The conventional exit status of a process stopped by `signal` (128 + signal: 130 for SIGINT,
// 143 for SIGTERM).
constexpr int exit_status_for(int signal) {
  return 128 + signal;
}

}  // namespace livod::daemon::runtime
