#pragma once
// How the estimator spreads independent work (residual rows, plane refits, point covariances)
// over the cores without owning a thread (DESIGN.md: the estimator never sees a thread). The
// daemon injects a TaskRunner backed by its worker pool; without one, everything runs on the
// calling thread.
//
// Results never depend on the runner or on how work is cut: every task writes only its own
// output slots, and whatever is summed is summed afterwards in item order. A replay with one
// thread and with two gives the same bytes.

#include <algorithm>
#include <cstddef>
#include <functional>

namespace livod::estimator {

class TaskRunner {
 public:
  TaskRunner() = default;
  TaskRunner(const TaskRunner&) = delete;
  TaskRunner& operator=(const TaskRunner&) = delete;
  virtual ~TaskRunner() = default;

  // Calls task(i) once for every i in [0, count), possibly on several threads at once, and
  // returns when every call has returned. Tasks must not throw. Not reentrant: a task must not
  // call run() on the same runner.
  virtual void run(std::size_t count, const std::function<void(std::size_t)>& task) = 0;
  // Threads that may run tasks at once (1: serial).
  [[nodiscard]] virtual int concurrency() const = 0;
};

class SerialTaskRunner final : public TaskRunner {
 public:
  void run(std::size_t count, const std::function<void(std::size_t)>& task) override {
    for (std::size_t i = 0; i < count; ++i) task(i);
  }
  [[nodiscard]] int concurrency() const override { return 1; }
};

// Calls fn(begin, end) on consecutive ranges covering [0, n), each of at least `grain` items
// (except a shorter last one); a few ranges per thread so that uneven ranges still balance.
inline void parallel_for(TaskRunner& runner, std::size_t n, std::size_t grain,
                         const std::function<void(std::size_t, std::size_t)>& fn) {
  if (n == 0) return;
  const std::size_t threads = static_cast<std::size_t>(std::max(1, runner.concurrency()));
  const std::size_t max_chunks =
      (n + std::max<std::size_t>(grain, 1) - 1) / std::max<std::size_t>(grain, 1);
  const std::size_t chunks = std::clamp<std::size_t>(4 * threads, 1, max_chunks);
  if (chunks <= 1 || threads == 1) {
    fn(0, n);
    return;
  }
  runner.run(chunks, [&](std::size_t c) { fn(c * n / chunks, (c + 1) * n / chunks); });
}

}  // namespace livod::estimator
