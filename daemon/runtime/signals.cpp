#include "daemon/runtime/signals.hpp"

#include <pthread.h>

namespace livod::daemon::runtime {

sigset_t BlockedSignals::handled() {
  sigset_t set;
  sigemptyset(&set);
  for (const int s : {SIGINT, SIGTERM, SIGHUP, SIGUSR1}) sigaddset(&set, s);
  return set;
}

BlockedSignals::BlockedSignals() : set_(handled()) {
  pthread_sigmask(SIG_BLOCK, &set_, &previous_);
}

BlockedSignals::~BlockedSignals() {
  timespec zero{};
  while (sigtimedwait(&set_, nullptr, &zero) > 0) {
  }
  pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
}

int BlockedSignals::wait(Nanoseconds timeout) const {
  timespec ts{};
  if (timeout.count() > 0) {
    ts.tv_sec = static_cast<time_t>(timeout.count() / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(timeout.count() % 1'000'000'000);
  }
  const int s = sigtimedwait(&set_, nullptr, &ts);
  return s > 0 ? s : 0;
}

}  // namespace livod::daemon::runtime
