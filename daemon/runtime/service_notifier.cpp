#include "daemon/runtime/service_notifier.hpp"

#include <fmt/core.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <cstdlib>
#include <utility>

namespace livod::daemon::runtime {
namespace {

const char* state_name(publish::SensorState s) {
  switch (s) {
    case publish::SensorState::kStreaming:
      return "STREAMING";
    case publish::SensorState::kStale:
      return "STALE";
    case publish::SensorState::kWaiting:
      break;
  }
  return "WAITING";
}

}  // namespace

std::string service_status_line(const HealthRecord& health, const HealthRecord* previous) {
  std::string line;
  for (const auto& s : health.sensors) {
    if (!line.empty()) line += ", ";
    line += s.name + " " + state_name(s.state);
  }
  if (!line.empty()) line += "; ";
  line += fmt::format("filter {}", to_string(health.estimator.status));
  if (previous != nullptr && health.host_time > previous->host_time) {
    const double seconds = to_seconds(health.host_time - previous->host_time);
    const auto frames = health.estimator.scans_processed - previous->estimator.scans_processed;
    line += fmt::format(" {:.1f} Hz", static_cast<double>(frames) / seconds);
  }
  return line;
}

ServiceNotifier::ServiceNotifier(Send send, std::optional<Nanoseconds> watchdog)
    : send_(std::move(send)), watchdog_(watchdog) {}

ServiceNotifier ServiceNotifier::from_environment() {
  std::optional<Nanoseconds> watchdog;
  std::uint64_t usec = 0;
  // > 0: WATCHDOG_USEC is set (and WATCHDOG_PID, if set, is this process).
  if (sd_watchdog_enabled(/*unset_environment=*/0, &usec) > 0 && usec > 0) {
    watchdog = Nanoseconds(static_cast<std::int64_t>(usec) * 1000);
  }
  if (std::getenv("NOTIFY_SOCKET") == nullptr) {
    // Not started by systemd as a notify service: nothing to tell, nobody to ping.
    return ServiceNotifier([](const std::string&) { return true; }, std::nullopt);
  }
  return ServiceNotifier(
      [](const std::string& state) {
        return sd_notify(/*unset_environment=*/0, state.c_str()) > 0;
      },
      watchdog);
}

void ServiceNotifier::watch(std::string name, std::function<std::uint64_t()> beats) {
  Watched w;
  w.name = std::move(name);
  w.beats = std::move(beats);
  w.at_last_ping = w.beats();
  watched_.push_back(std::move(w));
}

Nanoseconds ServiceNotifier::ping_interval() const {
  return watchdog_ ? Nanoseconds(watchdog_->count() / 2) : Nanoseconds(0);
}

void ServiceNotifier::send(const std::string& state) {
  if (send_(state)) return;
  // Logged once: NOTIFY_SOCKET names a socket nobody reads (a copied environment, not systemd).
  if (send_failures_++ == 0) {
    spdlog::warn("sd_notify: could not send to NOTIFY_SOCKET (further failures not logged)");
  }
}

void ServiceNotifier::ready(HostTime now, const std::string& status) {
  sent_status_ = status;
  send("READY=1\nSTATUS=" + status);
  last_ping_ = now;
  for (auto& w : watched_) w.at_last_ping = w.beats();
  // Idle threads beat every 20 ms (capture) and 100 ms (scheduler, publisher): a ping interval
  // close to that would be withheld now and then although nothing is stuck.
  constexpr Nanoseconds kShortestSafeInterval{500'000'000};
  if (watchdog_ && ping_interval() < kShortestSafeInterval) {
    spdlog::warn(
        "systemd watchdog: WatchdogSec={:.2f} s is below 1 s, too short for idle threads that "
        "beat every 100 ms (pings may be withheld although nothing is stuck)",
        to_seconds(*watchdog_));
  }
  if (watchdog_) {
    spdlog::info("systemd watchdog: {:.1f} s, pinged every {:.1f} s while {} thread(s) advance",
                 to_seconds(*watchdog_), to_seconds(ping_interval()), watched_.size());
  }
}

void ServiceNotifier::set_status(std::string status) {
  const std::lock_guard lock(status_mutex_);
  pending_status_ = std::move(status);
}

std::vector<std::string> ServiceNotifier::not_advanced() const {
  std::vector<std::string> names;
  for (const auto& w : watched_) {
    if (w.beats() == w.at_last_ping) names.push_back(w.name);
  }
  return names;
}

void ServiceNotifier::tick(HostTime now) {
  if (stopping_ || !last_ping_) return;
  std::string status;
  {
    const std::lock_guard lock(status_mutex_);
    status = pending_status_;
  }
  if (!status.empty() && status != sent_status_) {
    send("STATUS=" + status);
    sent_status_ = std::move(status);
  }
  if (!watchdog_ || now - *last_ping_ < ping_interval()) return;
  // "Advanced since the last ping", not "since the last check": a due ping that was withheld is
  // retried at every tick and sent as soon as every thread has beaten once since the last ping
  // sent, so a thread busy for less than half a period delays a ping but never costs one.
  const auto stuck = not_advanced();
  if (!stuck.empty()) {
    ++withheld_;
    if (!withheld_logged_) {
      std::string names;
      for (const auto& n : stuck) names += (names.empty() ? "" : ", ") + n;
      spdlog::error(
          "systemd watchdog: not pinging, no heartbeat for {:.1f} s from: {} (systemd restarts "
          "the service after {:.1f} s without a ping)",
          to_seconds(now - *last_ping_), names, to_seconds(*watchdog_));
      withheld_logged_ = true;
    }
    return;
  }
  if (withheld_logged_) {
    spdlog::warn("systemd watchdog: every thread advanced again after {:.1f} s; pinging",
                 to_seconds(now - *last_ping_));
    withheld_logged_ = false;
  }
  send("WATCHDOG=1");
  ++pings_;
  last_ping_ = now;
  for (auto& w : watched_) w.at_last_ping = w.beats();
}

void ServiceNotifier::stopping(const std::string& why) {
  if (stopping_) return;
  stopping_ = true;
  send("STOPPING=1\nSTATUS=stopping (" + why + ")");
}

}  // namespace livod::daemon::runtime
