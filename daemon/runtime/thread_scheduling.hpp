#pragma once
// Real-time scheduling of the daemon's own threads (the capture threads apply theirs themselves,
// drivers/capture/capture_thread.hpp) and memory locking. A refusal (no CAP_SYS_NICE, no
// RLIMIT_RTPRIO, a CPU outside the cpuset, a finite memlock limit) is reported, never fatal: the
// daemon runs on with normal scheduling.

#include <optional>
#include <string>

namespace livod::daemon::runtime {

// Applies SCHED_FIFO `priority` (1..99) and/or CPU affinity to the calling thread and names it.
// Returns what was refused and why (empty: everything requested was applied).
std::string apply_thread_scheduling(const std::string& name, std::optional<int> priority,
                                    std::optional<int> cpu);

// mlockall(MCL_CURRENT | MCL_FUTURE), only when RLIMIT_MEMLOCK is unlimited: under a finite limit
// every later allocation beyond it would fail (DESIGN.md traps). Returns the refusal or the error
// (empty: locked).
std::string lock_memory();

}  // namespace livod::daemon::runtime
