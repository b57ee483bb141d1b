#pragma once
// Process-wide logging setup. spdlog runs asynchronously (a bounded queue drained by one
// low-priority thread), so a log call costs a formatted copy on the caller; capture threads and
// decoders never log at all - they bump atomic counters that the health reporter turns into one
// line per health period at most (state changes at once, a summary every minute), so a flood of
// bad packets cannot flood the log.
//
// Under systemd (JOURNAL_STREAM names our stderr) the lines go to the journal with their
// priority, without the timestamp journald adds itself; elsewhere to stderr.

#include <string>

namespace livod::daemon {

struct LoggingConfig {
  std::string level = "info";  // trace, debug, info, warn, error, critical, off
  bool to_stderr = true;
  std::size_t queue_size = 8192;
};

// Installs the default async logger. Safe to call once per process; returns false (and keeps a
// synchronous stderr logger) if the level is not recognised.
bool init_logging(const LoggingConfig& config);

// Changes the level of the default logger (the configuration's logging.level, unless the command
// line gave one). Returns false, leaving the level, for an unknown name.
bool set_log_level(const std::string& level);

// Flushes and stops the async logger thread; called at the end of main.
void shutdown_logging();

}  // namespace livod::daemon
