#pragma once
// Counters with a single writer (a capture, device or camera thread) and any number of readers
// (health, STATUS=, tests): the writer updates them with plain relaxed stores, no locked
// read-modify-write on the capture path; readers see each value whole.

#include <atomic>

namespace livod {

template <class T>
void publish(std::atomic<T>& counter, T value) {
  counter.store(value, std::memory_order_relaxed);
}

template <class T>
void bump(std::atomic<T>& counter) {
  counter.store(counter.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

}  // namespace livod
