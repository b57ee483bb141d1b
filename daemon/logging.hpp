#pragma once
// Process-wide logging setup. spdlog runs asynchronously (a bounded queue drained by one
// low-priority thread), so a log call costs a formatted copy on the caller; capture threads never
// log at all - they bump atomic counters that the health reporter turns into log lines.

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

// Flushes and stops the async logger thread; called at the end of main.
void shutdown_logging();

}  // namespace livod::daemon
