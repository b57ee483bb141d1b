#pragma once
// A fixed pool of records handed from one thread to another without allocation or locks: the
// producer takes a free record, fills it in place (vectors keep their capacity from one use to
// the next) and publishes it; the consumer takes published records in order and gives them back.
// Two SPSC rings of pointers (free: consumer -> producer, full: producer -> consumer) carry them.
// When every record is in use the producer's acquire() fails: it drops what it wanted to send and
// the channel counts it (a slow consumer never blocks the producer).
//
// Threading: one producer thread (acquire, publish), one consumer thread (next, release).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/spsc_ring.hpp"

namespace livod::daemon::runtime {

template <class T>
class RecordChannel {
 public:
  // `prepare` is called once per record (e.g. to reserve vector capacity).
  template <class Prepare>
  RecordChannel(std::size_t capacity, Prepare prepare)
      : records_(capacity), free_(capacity), full_(capacity) {
    for (auto& r : records_) {
      prepare(r);
      free_.try_push(&r);
    }
  }
  explicit RecordChannel(std::size_t capacity) : RecordChannel(capacity, [](T&) {}) {}

  // Producer: a record to fill, or nullptr (counted in dropped()) when all are in use.
  T* acquire() {
    T* r = nullptr;
    if (!free_.try_pop(r)) {
      ++dropped_;
      return nullptr;
    }
    return r;
  }
  // Producer: hands a filled record to the consumer (always succeeds: it came from the pool).
  void publish(T* r) { full_.try_push(r); }

  // Consumer: the oldest published record, or nullptr.
  T* next() {
    T* r = nullptr;
    return full_.try_pop(r) ? r : nullptr;
  }
  // Consumer: gives a record back to the pool.
  void release(T* r) { free_.try_push(r); }

  // Producer thread only (a plain counter).
  [[nodiscard]] std::uint64_t dropped() const { return dropped_; }
  [[nodiscard]] std::size_t capacity() const { return records_.size(); }

 private:
  std::vector<T> records_;  // never resized: the pointers stay valid
  SpscRing<T*> free_;
  SpscRing<T*> full_;
  std::uint64_t dropped_ = 0;
};

}  // namespace livod::daemon::runtime
