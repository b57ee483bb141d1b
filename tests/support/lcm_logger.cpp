#include "tests/support/lcm_logger.hpp"

#include <lcm/lcm-cpp.hpp>

#include <csignal>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "io/lcm_log.hpp"

namespace livod::test {

namespace {

bool probe_recorded(const std::filesystem::path& log) {
  std::error_code ec;
  if (!std::filesystem::exists(log, ec)) return false;
  io::LcmLogReaderOptions options;
  options.on_corruption = io::LcmLogCorruption::kResync;  // the logger may be mid-write
  io::LcmLogReader reader(log, options);
  while (const auto e = reader.next()) {
    if (e->channel == LcmLoggerProcess::kProbeChannel) return true;
  }
  return false;
}

std::filesystem::path output_of(const std::filesystem::path& log) {
  return std::filesystem::path(log.string() + ".txt");
}

}  // namespace

LcmLoggerProcess::LcmLoggerProcess(const std::string& url, std::filesystem::path log,
                                   std::chrono::milliseconds timeout)
    : log_(std::move(log)),
      // `lcm-logger -l URL` is broken in LCM 1.3.1; --lcm-url works.
      process_({"lcm-logger", "--quiet", "--force", "--flush-interval=50", "--lcm-url=" + url,
                log_.string()},
               {.output = output_of(log_)}) {
  lcm::LCM probe(url);
  if (!probe.good()) throw std::runtime_error("cannot open LCM on '" + url + "' for the probe");
  const std::uint8_t byte = 0;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (!process_.running()) {
      throw std::runtime_error("lcm-logger exited: " + read_text_file(output_of(log_)));
    }
    probe.publish(kProbeChannel, &byte, 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (probe_recorded(log_)) return;
  }
  throw std::runtime_error("lcm-logger recorded nothing on '" + url + "' within " +
                           std::to_string(timeout.count()) +
                           " ms: " + read_text_file(output_of(log_)));
}

void LcmLoggerProcess::stop(std::chrono::milliseconds settle) {
  std::this_thread::sleep_for(settle);
  process_.signal(SIGINT);
  if (!process_.wait_for(std::chrono::seconds(3))) {
    throw std::runtime_error("lcm-logger did not exit on SIGINT within 3 s");
  }
}

}  // namespace livod::test
