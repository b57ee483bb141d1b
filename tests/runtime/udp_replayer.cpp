#include "tests/runtime/udp_replayer.hpp"

#include <chrono>
#include <optional>
#include <random>
#include <thread>

#include "io/pcap.hpp"
#include "io/udp_socket.hpp"

namespace livod::test {
namespace {

// One capture being sent: its reader, the next datagram it routes, its faults' state.
struct Pending {
  const CaptureStream* capture = nullptr;
  io::PcapReader reader;
  std::optional<io::UdpDatagram> next;
  const UdpRoute* route = nullptr;
  std::mt19937_64 rng;
  std::uint64_t real = 0;

  // Advances to the next datagram with a route; nullopt at the end of the file.
  void advance() {
    while ((next = reader.next())) {
      route = nullptr;
      for (const auto& rt : capture->routes) {
        if (rt.pcap_port == next->dst_port) route = &rt;
      }
      if (route != nullptr) return;
    }
  }
};

}  // namespace

SenderResult send_capture(const std::filesystem::path& pcap, const std::vector<UdpRoute>& routes,
                          const ReplayFaults& faults, const std::stop_token& stop) {
  return send_captures({CaptureStream{pcap, routes, faults}}, stop).front();
}

std::vector<SenderResult> send_captures(const std::vector<CaptureStream>& captures,
                                        const std::stop_token& stop) {
  io::UdpSocket socket(io::UdpSocketConfig{.bind_address = "127.0.0.1",
                                           .receive_buffer_bytes = 4096,
                                           .batch_size = 1,
                                           .max_datagram_bytes = 1});
  std::vector<Pending> pending;
  pending.reserve(captures.size());
  std::optional<std::int64_t> first_ns;
  for (const auto& c : captures) {
    pending.push_back(Pending{&c, io::PcapReader(c.pcap), std::nullopt, nullptr,
                              std::mt19937_64(c.faults.seed), 0});
    pending.back().advance();
    if (const auto& d = pending.back().next) {
      first_ns = std::min(first_ns.value_or(d->capture_time_ns), d->capture_time_ns);
    }
  }
  std::vector<SenderResult> results(captures.size());
  std::vector<std::byte> junk;
  const auto start = std::chrono::steady_clock::now();
  while (!stop.stop_requested()) {
    // The capture whose next datagram is the earliest.
    std::size_t i = pending.size();
    for (std::size_t k = 0; k < pending.size(); ++k) {
      if (pending[k].next && (i == pending.size() || pending[k].next->capture_time_ns <
                                                         pending[i].next->capture_time_ns)) {
        i = k;
      }
    }
    if (i == pending.size()) break;
    Pending& p = pending[i];
    SenderResult& r = results[i];
    const ReplayFaults& faults = p.capture->faults;
    const io::UdpDatagram& d = *p.next;
    const double t = static_cast<double>(d.capture_time_ns - *first_ns) * 1e-9;
    r.span_s = t;
    std::this_thread::sleep_until(start + std::chrono::nanoseconds(d.capture_time_ns - *first_ns));
    if (t >= faults.silent_from_s && t < faults.silent_to_s) {
      ++r.silenced;
      p.advance();
      continue;
    }
    if (socket.send_to(0x7F000001, p.route->local_port, d.payload)) ++r.sent;
    ++p.real;
    if (faults.malformed_every > 0 &&
        p.real % static_cast<std::uint64_t>(faults.malformed_every) == 0) {
      // Random bytes, shorter than any packet header (< 32 B) or longer than the real packet: a
      // length no packet of the port has, so no decoder may take it.
      const std::size_t n =
          p.rng() % 2 == 0 ? 1 + p.rng() % 31 : d.payload.size() + 1 + p.rng() % 64;
      junk.resize(n);
      for (auto& b : junk) b = static_cast<std::byte>(p.rng());
      if (socket.send_to(0x7F000001, p.route->local_port, junk)) ++r.malformed;
    }
    p.advance();
  }
  return results;
}

}  // namespace livod::test
