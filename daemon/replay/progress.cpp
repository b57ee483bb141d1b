#include "daemon/replay/progress.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <cstdio>

namespace livod::daemon::replay {
namespace {

constexpr auto kRedrawPeriod = std::chrono::milliseconds(200);

}  // namespace

ProgressLine::ProgressLine(bool enabled)
    : enabled_(enabled), start_(std::chrono::steady_clock::now()), next_draw_(start_) {}

void ProgressLine::update(const ProgressState& state) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_draw_) return;
  next_draw_ = now + kRedrawPeriod;
  draw(state);
}

void ProgressLine::finish(const ProgressState& state) {
  if (!enabled_) return;
  draw(state);
  std::fputs("\n", stderr);
  std::fflush(stderr);
}

void ProgressLine::draw(const ProgressState& state) {
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::string percent =
      state.fraction ? fmt::format("{:5.1f} % ", 100.0 * *state.fraction) : std::string();
  const std::string line = fmt::format(
      "\rreplay {}{:8.1f} s of data in {:6.1f} s ({:5.1f}x)  frames {:6}  last {:6.2f} ms  {}",
      percent, state.recording_s, wall, wall > 0.0 ? state.recording_s / wall : 0.0, state.frames,
      state.last_frame_ms, state.status);
  // Pad to clear the rest of a longer previous line; ESC[K would do it too, on fewer terminals.
  fmt::print(stderr, "{:<110}", line);
  std::fflush(stderr);
}

bool stderr_is_tty() {
  return isatty(STDERR_FILENO) == 1;
}

}  // namespace livod::daemon::replay
