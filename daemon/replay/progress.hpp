#pragma once
// The replay's progress line on stderr, redrawn in place (carriage return) at most five times a
// second, and only when stderr is a terminal: logs and CI output stay free of it.

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>

namespace livod::daemon::replay {

struct ProgressState {
  double recording_s = 0.0;        // receive-time span replayed so far
  std::optional<double> fraction;  // of the whole recording, when a source can tell
  std::size_t frames = 0;
  double last_frame_ms = 0.0;
  std::string status;  // e.g. "waiting for IMU initialisation"
};

class ProgressLine {
 public:
  // enabled: draw at all (the caller passes isatty(STDERR_FILENO) unless told to be quiet).
  explicit ProgressLine(bool enabled);
  // Cheap unless a redraw is due.
  void update(const ProgressState& state);
  // Ends the line (a final redraw and a newline) if anything was drawn.
  void finish(const ProgressState& state);

 private:
  void draw(const ProgressState& state);

  bool enabled_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point next_draw_;
};

// True when stderr is a terminal.
bool stderr_is_tty();

}  // namespace livod::daemon::replay
