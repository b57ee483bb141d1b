#include "drivers/camera/frame_ring.hpp"

#include <cstring>
#include <stdexcept>

namespace livod::camera {
namespace {

std::size_t round_up(std::size_t n, std::size_t to) {
  return (n + to - 1) / to * to;
}

}  // namespace

FrameRing::FrameRing(std::size_t capacity, std::size_t slot_bytes)
    : ring_(capacity),
      slot_bytes_(slot_bytes),
      stride_(round_up(slot_bytes, kCacheLineBytes)),
      slot_count_(capacity + 1) {
  if (slot_bytes == 0) throw std::invalid_argument("FrameRing: slot_bytes must be > 0");
  arena_ = std::make_unique<std::byte[]>(stride_ * slot_count_);
  // Commit every page now: the capture thread must not page-fault in steady state.
  std::memset(arena_.get(), 0, stride_ * slot_count_);
}

std::span<std::byte> FrameRing::begin_write() {
  if (ring_.size_approx() >= ring_.capacity()) {
    overruns_.store(overruns_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    have_slot_ = false;
    return {};
  }
  have_slot_ = true;
  return {arena_.get() + next_slot_ * stride_, slot_bytes_};
}

void FrameRing::commit(const FrameInfo& info) {
  const std::size_t bytes = static_cast<std::size_t>(info.height) * info.stride;
  if (!have_slot_ || bytes > slot_bytes_ || info.height < 0) {
    throw std::invalid_argument("FrameRing::commit without a slot or beyond the slot size");
  }
  const std::byte* slot = arena_.get() + next_slot_ * stride_;
  // Cannot fail: begin_write saw room, and only this thread adds frames.
  ring_.try_push(Entry{info, {slot, bytes}});
  next_slot_ = next_slot_ + 1 == slot_count_ ? 0 : next_slot_ + 1;
  have_slot_ = false;
}

}  // namespace livod::camera
