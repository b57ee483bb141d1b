#include "daemon/logging.hpp"

#include <spdlog/async.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/sinks/systemd_sink.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <optional>

namespace livod::daemon {

namespace {

std::optional<spdlog::level::level_enum> parse_level(const std::string& name) {
  const auto level = spdlog::level::from_str(name);
  if (spdlog::level::to_string_view(level) == name ||
      (name == "warn" && level == spdlog::level::warn)) {
    return level;
  }
  return std::nullopt;
}

// systemd sets JOURNAL_STREAM to "<device>:<inode>" of the journal stream it connected to
// stderr: when stderr is still that stream, lines go to the journal natively.
bool stderr_is_journal() {
  const char* env = std::getenv("JOURNAL_STREAM");
  if (env == nullptr) return false;
  struct stat st {};
  if (fstat(STDERR_FILENO, &st) != 0) return false;
  unsigned long long dev = 0;
  unsigned long long ino = 0;
  if (std::sscanf(env, "%llu:%llu", &dev, &ino) != 2) return false;
  return static_cast<unsigned long long>(st.st_dev) == dev &&
         static_cast<unsigned long long>(st.st_ino) == ino;
}

}  // namespace

bool init_logging(const LoggingConfig& config) {
  const auto level = parse_level(config.level);
  spdlog::init_thread_pool(config.queue_size, 1);
  spdlog::sink_ptr sink;
  const bool journal = stderr_is_journal();
  if (journal) {
    sink = std::make_shared<spdlog::sinks::systemd_sink_mt>("livod");
  } else {
    sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  }
  auto logger = std::make_shared<spdlog::async_logger>("livod", sink, spdlog::thread_pool(),
                                                       spdlog::async_overflow_policy::block);
  logger->set_level(level.value_or(spdlog::level::info));
  logger->set_pattern(journal ? "%v" : "[%Y-%m-%d %H:%M:%S.%e] [%^%l%$] %v");
  spdlog::set_default_logger(logger);
  return level.has_value();
}

bool set_log_level(const std::string& name) {
  const auto level = parse_level(name);
  if (!level) return false;
  spdlog::set_level(*level);
  return true;
}

void shutdown_logging() {
  spdlog::shutdown();
}

}  // namespace livod::daemon
