#include "tests/runtime/udp_replayer.hpp"

#include <chrono>
#include <random>
#include <thread>

#include "io/pcap.hpp"
#include "io/udp_socket.hpp"

namespace livod::test {

SenderResult send_capture(const std::filesystem::path& pcap, const std::vector<UdpRoute>& routes,
                          const ReplayFaults& faults, const std::stop_token& stop) {
  io::PcapReader reader(pcap);
  io::UdpSocket socket(io::UdpSocketConfig{.bind_address = "127.0.0.1",
                                           .receive_buffer_bytes = 4096,
                                           .batch_size = 1,
                                           .max_datagram_bytes = 1});
  std::mt19937_64 rng(faults.seed);
  std::vector<std::byte> junk;
  SenderResult r;
  std::optional<std::int64_t> first_ns;
  const auto start = std::chrono::steady_clock::now();
  std::uint64_t real = 0;
  while (auto d = reader.next()) {
    if (stop.stop_requested()) break;
    const UdpRoute* route = nullptr;
    for (const auto& rt : routes) {
      if (rt.pcap_port == d->dst_port) route = &rt;
    }
    if (route == nullptr) continue;
    if (!first_ns) first_ns = d->capture_time_ns;
    const double t = static_cast<double>(d->capture_time_ns - *first_ns) * 1e-9;
    r.span_s = t;
    std::this_thread::sleep_until(start + std::chrono::nanoseconds(d->capture_time_ns - *first_ns));
    if (t >= faults.silent_from_s && t < faults.silent_to_s) {
      ++r.silenced;
      continue;
    }
    if (socket.send_to(0x7F000001, route->local_port, d->payload)) ++r.sent;
    ++real;
    if (faults.malformed_every > 0 &&
        real % static_cast<std::uint64_t>(faults.malformed_every) == 0) {
      // Random bytes, shorter than any packet header (< 32 B) or longer than the real packet: a
      // length no packet of the port has, so no decoder may take it.
      const std::size_t n = rng() % 2 == 0 ? 1 + rng() % 31 : d->payload.size() + 1 + rng() % 64;
      junk.resize(n);
      for (auto& b : junk) b = static_cast<std::byte>(rng());
      if (socket.send_to(0x7F000001, route->local_port, junk)) ++r.malformed;
    }
  }
  return r;
}

}  // namespace livod::test
