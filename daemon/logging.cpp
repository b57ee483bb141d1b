#include "daemon/logging.hpp"

#include <spdlog/async.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

namespace livod::daemon {

bool init_logging(const LoggingConfig& config) {
  const auto level = spdlog::level::from_str(config.level);
  const bool level_ok = spdlog::level::to_string_view(level) == config.level ||
                        (config.level == "warn" && level == spdlog::level::warn);
  spdlog::init_thread_pool(config.queue_size, 1);
  auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  auto logger = std::make_shared<spdlog::async_logger>("livod", sink, spdlog::thread_pool(),
                                                       spdlog::async_overflow_policy::block);
  logger->set_level(level_ok ? level : spdlog::level::info);
  logger->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%^%l%$] %v");
  spdlog::set_default_logger(logger);
  return level_ok;
}

void shutdown_logging() { spdlog::shutdown(); }

}  // namespace livod::daemon
