#pragma once
// livod::camera::FrameRing - the camera capture thread's pre-allocated image pool: a bounded
// single-producer/single-consumer queue of frames with fixed-size pixel slots, all allocated (and
// every page touched) by the constructor. The producer writes a frame's pixels straight into a
// free slot (the one copy: a conversion from the driver's buffer, or a memcpy), then commits the
// metadata; the consumer reads the pixels in place and pops. A full ring drops the newest frame
// and counts it; nothing ever blocks.
//
// Layout and why no extra synchronisation is needed: as drivers/capture/packet_ring.hpp, a core
// SpscRing of small descriptors plus an arena of capacity + 1 slots, the k-th committed frame in
// slot k mod (capacity + 1). begin_write() hands out that slot only when the producer sees fewer
// than `capacity` frames queued (SpscRing::size_approx loads the consumer index with acquire),
// which proves frame k - capacity - 1, the slot's previous user, has been popped and that its pop
// happened-before the new writes; commit()'s release publication makes the pixels visible.
//
// Threading: one producer calls begin_write/commit; one consumer calls front/pop; anyone may call
// the const accessors. Create before the threads, destroy after joining them.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "core/spsc_ring.hpp"
#include "drivers/camera/camera_frame.hpp"

namespace livod::camera {

class FrameRing {
 public:
  struct Entry {
    FrameInfo info;
    std::span<const std::byte> pixels;  // info.height rows of info.stride bytes, in the slot
  };

  // Throws std::invalid_argument for capacity or slot_bytes 0.
  FrameRing(std::size_t capacity, std::size_t slot_bytes);
  FrameRing(const FrameRing&) = delete;
  FrameRing& operator=(const FrameRing&) = delete;

  // ---- producer ------------------------------------------------------------------------------
  // The slot for the next frame, or an empty span when the ring is full (the frame is dropped and
  // counted in overruns()).
  std::span<std::byte> begin_write();
  // Queues the frame written into the slot of the last successful begin_write(); the pixels are
  // info.height * info.stride bytes (<= slot_bytes(), else std::invalid_argument).
  void commit(const FrameInfo& info);

  // ---- consumer ------------------------------------------------------------------------------
  [[nodiscard]] const Entry* front() { return ring_.front(); }
  void pop() { ring_.pop(); }

  // ---- any thread ----------------------------------------------------------------------------
  [[nodiscard]] std::size_t capacity() const { return ring_.capacity(); }
  [[nodiscard]] std::size_t slot_bytes() const { return slot_bytes_; }
  [[nodiscard]] std::size_t size_approx() const { return ring_.size_approx(); }
  [[nodiscard]] std::uint64_t overruns() const { return overruns_.load(std::memory_order_relaxed); }

 private:
  SpscRing<Entry> ring_;
  std::size_t slot_bytes_;
  std::size_t stride_;
  std::size_t slot_count_;
  std::unique_ptr<std::byte[]> arena_;
  // Producer-only state, on its own line.
  alignas(kCacheLineBytes) std::size_t next_slot_ = 0;
  bool have_slot_ = false;
  std::atomic<std::uint64_t> overruns_{0};
};

}  // namespace livod::camera
