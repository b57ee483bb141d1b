#pragma once
// The systemd service manager protocol (sd_notify(3)) for `livod run` as a Type=notify service:
//
//   READY=1      once the configuration is loaded, every socket is bound and every thread runs;
//   STATUS=...   one line: each sensor's state and the filter rate (refreshed at the health
//                period, shown by `systemctl status livod`);
//   WATCHDOG=1   every half WATCHDOG_USEC, but only if every watched thread (each capture thread,
//                the scheduler, the publisher) advanced its heartbeat since the previous ping: a
//                stuck thread stops the pings and systemd restarts the service (WatchdogSec=);
//   STOPPING=1   when a stop begins (SIGTERM, SIGINT, ...).
//
// Idle is not stuck: capture threads beat on every poll wakeup (20 ms) even on a silent socket and
// the scheduler on every idle turn (<= 100 ms), so a sensor that sends nothing keeps the pings
// going while a scheduler inside one step for half a watchdog period stops them.
//
// The class is clock-free and transport-free for its tests: the caller passes `now` and the
// function that sends a notification; from_environment() gives the real one (libsystemd's
// sd_notify, which honours NOTIFY_SOCKET, and sd_watchdog_enabled, which honours WATCHDOG_USEC and
// WATCHDOG_PID). Without NOTIFY_SOCKET every call is a no-op.

#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "daemon/runtime/records.hpp"

namespace livod::daemon::runtime {

// "mid360 STREAMING; filter OK 10.0 Hz" from a health record; the filter rate is the frames
// processed since `previous` (none: not shown).
[[nodiscard]] std::string service_status_line(const HealthRecord& health,
                                              const HealthRecord* previous);

class ServiceNotifier {
 public:
  // Sends one notification ("READY=1", "WATCHDOG=1", ...); false when it could not be sent.
  using Send = std::function<bool(const std::string&)>;

  // `watchdog`: WATCHDOG_USEC, or nullopt when systemd does not watch the service.
  ServiceNotifier(Send send, std::optional<Nanoseconds> watchdog);

  // sd_notify and sd_watchdog_enabled (a no-op sender when NOTIFY_SOCKET is unset).
  [[nodiscard]] static ServiceNotifier from_environment();

  // A heartbeat that must advance between two pings (call before ready()).
  void watch(std::string name, std::function<std::uint64_t()> beats);

  // READY=1, with the first status line; the watchdog period starts here.
  void ready(HostTime now, const std::string& status);
  // Any thread (the publisher, at each health record): the next tick() sends it if it changed.
  void set_status(std::string status);
  // The thread that owns the notifier, often (every 100 ms in the daemon): sends a new status,
  // and pings the watchdog when it is due and every watched heartbeat advanced.
  void tick(HostTime now);
  // STOPPING=1 with a status saying why; no ping after this.
  void stopping(const std::string& why);

  [[nodiscard]] bool watchdog_enabled() const { return watchdog_.has_value(); }
  // Half of WATCHDOG_USEC (systemd's advice); 0 without watchdog.
  [[nodiscard]] Nanoseconds ping_interval() const;
  [[nodiscard]] std::uint64_t pings() const { return pings_; }
  // Due pings not sent because some heartbeat had not advanced (counted once per tick).
  [[nodiscard]] std::uint64_t withheld() const { return withheld_; }

 private:
  struct Watched {
    std::string name;
    std::function<std::uint64_t()> beats;
    std::uint64_t at_last_ping = 0;
  };
  // The names of the watched threads that did not advance since the last ping (empty: all did).
  [[nodiscard]] std::vector<std::string> not_advanced() const;
  void send(const std::string& state);

  Send send_;
  std::optional<Nanoseconds> watchdog_;
  std::vector<Watched> watched_;
  std::optional<HostTime> last_ping_;  // or READY=1
  bool stopping_ = false;
  bool withheld_logged_ = false;
  std::uint64_t pings_ = 0;
  std::uint64_t withheld_ = 0;
  std::uint64_t send_failures_ = 0;
  std::string sent_status_;
  std::mutex status_mutex_;  // pending_status_ is written by the publisher thread
  std::string pending_status_;
};

}  // namespace livod::daemon::runtime
