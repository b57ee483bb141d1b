#include "daemon/runtime/heartbeat.hpp"

namespace livod::daemon::runtime {

void HeartbeatMonitor::add(std::string name, std::function<std::uint64_t()> read) {
  Entry e;
  e.name = std::move(name);
  e.read = std::move(read);
  e.last = e.read();
  e.at_last_check = e.last;
  entries_.push_back(std::move(e));
}

std::vector<ThreadBeat> HeartbeatMonitor::update(HostTime now) {
  std::vector<ThreadBeat> out;
  out.reserve(entries_.size());
  for (Entry& e : entries_) {
    const std::uint64_t beats = e.read();
    if (beats != e.last || !e.moved) {
      e.last = beats;
      e.moved = now;
    }
    ThreadBeat b;
    b.name = e.name;
    b.beats = beats;
    b.age = now - *e.moved;
    b.stuck = b.age > stuck_after_;
    out.push_back(std::move(b));
  }
  return out;
}

bool HeartbeatMonitor::advanced_since_last() {
  bool all = true;
  for (Entry& e : entries_) {
    const std::uint64_t beats = e.read();
    if (beats == e.at_last_check) all = false;
    e.at_last_check = beats;
  }
  return all;
}

}  // namespace livod::daemon::runtime
