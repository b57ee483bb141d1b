#pragma once
// livod::SpscRing<T> - bounded, lock-free single-producer / single-consumer ring.
//
// This is how a capture thread hands measurements to the scheduler (DESIGN.md "Data flow"):
// the producer never blocks and never allocates; when the ring is full the push fails, the item
// is dropped by the caller and the ring counts an overrun that the health thread reports.
//
// Threading contract
//   * exactly one producer thread calls try_push / try_emplace;
//   * exactly one consumer thread calls try_pop / front / pop;
//   * any thread may call capacity(), size_approx(), empty_approx() and overruns().
//   Construction and destruction must happen-before / happen-after every other use (create the
//   ring before starting the threads, destroy it after joining them).
//
// Progress: every operation is wait-free (a bounded number of steps, no retry loops, no locks).
// Memory: all slots are allocated by the constructor; nothing is allocated afterwards.
//
// Memory ordering: only acquire/release (plus relaxed loads of an index by its own writer, and
// the relaxed statistics counter). No seq_cst and no fences, so that ThreadSanitizer models the
// synchronisation exactly (it does not understand stand-alone fences) and so that x86 needs no
// locked instructions on the hot path.
//   producer: construct item in slot w, then write_index.store(w+1, release)  -- publishes item
//   consumer: write_index.load(acquire) sees w+1 => the item's construction is visible
//   consumer: destroy item in slot r, then read_index.store(r+1, release)     -- frees the slot
//   producer: read_index.load(acquire) sees r+1 => the destruction happened before the slot is
//             reused
//
// Layout: the producer-owned index (with the producer's cached copy of the consumer index and the
// overrun counter) and the consumer-owned index (with its cached copy of the producer index)
// live on separate cache lines, so the two threads only exchange cache lines when one of them
// actually has to refresh its cached copy (the ring looked full or empty).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <stdexcept>
#include <utility>

namespace livod {

// Size that keeps two hot variables from false sharing. std::hardware_destructive_interference_size
// is not used: GCC 12 warns about it in headers (its value may change with -mtune, which would
// silently change this class's layout between translation units) and clang 14's libstdc++ build
// lacks it. 64 bytes is the L1 line size of every x86-64 and of the common ARMv8 cores.
inline constexpr std::size_t kCacheLineBytes = 64;

template <class T>
class SpscRing {
 public:
  using value_type = T;

  // Holds up to `capacity` items (>= 1). Allocates all storage here; throws std::invalid_argument
  // for capacity 0 and std::bad_alloc if the storage cannot be allocated.
  explicit SpscRing(std::size_t capacity)
      : capacity_(checked_capacity(capacity)),
        // One slot stays empty so that "full" (write + 1 == read) differs from "empty"
        // (write == read) using the two indices alone.
        slot_count_(capacity_ + 1),
        slots_(static_cast<Slot*>(::operator new(slot_count_ * sizeof(Slot), kStorageAlignment))) {}

  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;
  SpscRing(SpscRing&&) = delete;
  SpscRing& operator=(SpscRing&&) = delete;

  // Destroys the items still in the ring. Runs after both threads are done (see contract), so
  // relaxed loads are enough here.
  ~SpscRing() {
    std::size_t read = read_.index.load(std::memory_order_relaxed);
    const std::size_t write = write_.index.load(std::memory_order_relaxed);
    while (read != write) {
      std::destroy_at(item(read));
      read = next(read);
    }
    ::operator delete(slots_, kStorageAlignment);
  }

  // ---- producer side --------------------------------------------------------------------------

  // Copies `value` into the ring. Returns false (and counts an overrun) if the ring is full.
  bool try_push(const T& value) { return try_emplace(value); }

  // Moves `value` into the ring. Returns false (and counts an overrun) if the ring is full; in
  // that case `value` has not been moved from.
  bool try_push(T&& value) { return try_emplace(std::move(value)); }

  // Constructs a T in place from `args`. Returns false (and counts an overrun) if the ring is
  // full; the arguments are then left untouched. If T's constructor throws, the ring is unchanged.
  template <class... Args>
  bool try_emplace(Args&&... args) {
    // Only this thread writes write_.index, so a relaxed load of it is exact.
    const std::size_t write = write_.index.load(std::memory_order_relaxed);
    const std::size_t after = next(write);
    if (after == write_.cached_read) {
      // Looks full with the cached consumer position: refresh it (the only cross-core read).
      write_.cached_read = read_.index.load(std::memory_order_acquire);
      if (after == write_.cached_read) {
        // Single writer: load + store instead of a locked read-modify-write.
        write_.overruns.store(write_.overruns.load(std::memory_order_relaxed) + 1,
                              std::memory_order_relaxed);
        return false;
      }
    }
    ::new (static_cast<void*>(slots_[write].bytes)) T(std::forward<Args>(args)...);
    write_.index.store(after, std::memory_order_release);
    return true;
  }

  // ---- consumer side --------------------------------------------------------------------------

  // Moves the oldest item into `out` and removes it. Returns false if the ring is empty.
  bool try_pop(T& out) {
    T* const oldest = front();
    if (oldest == nullptr) return false;
    out = std::move(*oldest);
    pop();
    return true;
  }

  // The oldest item, for in-place use by the consumer (large items such as scans need not be
  // copied), or nullptr if the ring is empty. The pointer stays valid until pop().
  [[nodiscard]] T* front() {
    const std::size_t read = read_.index.load(std::memory_order_relaxed);
    if (read == read_.cached_write) {
      read_.cached_write = write_.index.load(std::memory_order_acquire);
      if (read == read_.cached_write) return nullptr;
    }
    return item(read);
  }

  // Destroys and removes the oldest item. Precondition: the last front() returned non-null (or a
  // try_pop-free check proved the ring non-empty); calling it on an empty ring is undefined.
  void pop() {
    const std::size_t read = read_.index.load(std::memory_order_relaxed);
    std::destroy_at(item(read));
    read_.index.store(next(read), std::memory_order_release);
  }

  // ---- any thread -----------------------------------------------------------------------------

  [[nodiscard]] std::size_t capacity() const { return capacity_; }

  // Number of items at some instant during the call (exact when called by the producer or the
  // consumer while the other side is idle). For monitoring only: it may be stale by the time it
  // returns.
  [[nodiscard]] std::size_t size_approx() const {
    const std::size_t read = read_.index.load(std::memory_order_acquire);
    const std::size_t write = write_.index.load(std::memory_order_acquire);
    return write >= read ? write - read : write + slot_count_ - read;
  }

  [[nodiscard]] bool empty_approx() const { return size_approx() == 0; }

  // Pushes that failed because the ring was full, since construction. Relaxed is enough: the
  // counter publishes no other data (nobody reads slots because of its value), it only has to
  // be untorn and monotonic, which any atomic access guarantees; readers see it eventually.
  [[nodiscard]] std::uint64_t overruns() const {
    return write_.overruns.load(std::memory_order_relaxed);
  }

 private:
  // Raw, suitably aligned storage for one T; the ring constructs and destroys the T explicitly.
  struct Slot {
    alignas(T) std::byte bytes[sizeof(T)];
  };

  // Storage starts on a cache line, so items whose size is a multiple of a line (64 B IMU
  // samples, say) never straddle two lines that the producer and the consumer touch at once.
  static constexpr std::align_val_t kStorageAlignment{
      alignof(Slot) > kCacheLineBytes ? alignof(Slot) : kCacheLineBytes};

  static std::size_t checked_capacity(std::size_t capacity) {
    if (capacity == 0) throw std::invalid_argument("SpscRing: capacity must be at least 1");
    if (capacity > (SIZE_MAX / sizeof(Slot)) - 1) throw std::bad_array_new_length();
    return capacity;
  }

  [[nodiscard]] std::size_t next(std::size_t index) const {
    // A compare instead of a modulo: capacity is arbitrary (not a power of two).
    const std::size_t after = index + 1;
    return after == slot_count_ ? 0 : after;
  }

  [[nodiscard]] T* item(std::size_t index) const {
    return std::launder(reinterpret_cast<T*>(slots_[index].bytes));
  }

  // Written only by the producer.
  struct alignas(kCacheLineBytes) ProducerSide {
    std::atomic<std::size_t> index{0};
    std::size_t cached_read = 0;  // last consumer index the producer has seen
    std::atomic<std::uint64_t> overruns{0};
  };
  // Written only by the consumer.
  struct alignas(kCacheLineBytes) ConsumerSide {
    std::atomic<std::size_t> index{0};
    std::size_t cached_write = 0;  // last producer index the consumer has seen
  };

  // Read-only after construction, shared by both threads (its own line: never invalidated).
  alignas(kCacheLineBytes) const std::size_t capacity_;
  const std::size_t slot_count_;
  Slot* const slots_;

  ProducerSide write_;
  ConsumerSide read_;
};

}  // namespace livod
