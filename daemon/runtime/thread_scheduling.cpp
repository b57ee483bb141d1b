#include "daemon/runtime/thread_scheduling.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>

namespace livod::daemon::runtime {

std::string apply_thread_scheduling(const std::string& name, std::optional<int> priority,
                                    std::optional<int> cpu) {
  const pthread_t self = pthread_self();
  // The kernel keeps 15 characters; a longer name is refused, so cut it.
  pthread_setname_np(self, name.substr(0, 15).c_str());
  std::string refused;
  if (cpu) {
    int rc = EINVAL;
    if (*cpu >= 0 && *cpu < CPU_SETSIZE) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(static_cast<std::size_t>(*cpu), &set);
      rc = pthread_setaffinity_np(self, sizeof(set), &set);
    }
    if (rc != 0) {
      refused += "CPU " + std::to_string(*cpu) + " refused (" + std::strerror(rc) + ")";
    }
  }
  if (priority) {
    sched_param param{};
    param.sched_priority = *priority;
    const int rc = pthread_setschedparam(self, SCHED_FIFO, &param);
    if (rc != 0) {
      if (!refused.empty()) refused += "; ";
      refused += "SCHED_FIFO priority " + std::to_string(*priority) + " refused (" +
                 std::strerror(rc) +
                 (rc == EPERM ? ": needs CAP_SYS_NICE or LimitRTPRIO= in the unit)" : ")");
    }
  }
  return refused;
}

std::string lock_memory() {
  rlimit limit{};
  if (getrlimit(RLIMIT_MEMLOCK, &limit) != 0)
    return std::string("getrlimit: ") + std::strerror(errno);
  if (limit.rlim_cur != RLIM_INFINITY) {
    return "memory not locked: RLIMIT_MEMLOCK is " + std::to_string(limit.rlim_cur) +
           " bytes, not unlimited (LimitMEMLOCK=infinity in the unit); locking under a finite "
           "limit would make later allocations fail";
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    return std::string("mlockall: ") + std::strerror(errno);
  }
  return {};
}

}  // namespace livod::daemon::runtime
