#include "drivers/capture/pcap_pacer.hpp"

#include <algorithm>
#include <chrono>
#include <optional>
#include <stdexcept>
#include <thread>

#include "io/pcap.hpp"
#include "io/udp_socket.hpp"

namespace livod::drivers::capture {
namespace {

// Longest single sleep, so that a stop request is noticed within this time.
constexpr auto kMaxSleep = std::chrono::milliseconds(20);

// Sleeps until `deadline` or a stop request; false if stopped.
bool sleep_until(std::chrono::steady_clock::time_point deadline, const std::stop_token& stop) {
  for (;;) {
    if (stop.stop_requested()) return false;
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return true;
    std::this_thread::sleep_for(
        std::min<std::chrono::steady_clock::duration>(deadline - now, kMaxSleep));
  }
}

// Reads `capture` and calls deliver(datagram) for each routed datagram at its scheduled time.
// `route` maps a datagram to a destination (nullopt = unrouted); deliver returns success.
template <class Route, class Deliver>
PaceResult pace(const std::filesystem::path& capture, const PaceOptions& options,
                const std::stop_token& stop, Route route, Deliver deliver) {
  if (!(options.speed > 0.0)) throw std::invalid_argument("pcap pacer: speed must be > 0");
  io::PcapReader reader(capture);
  PaceResult result;
  std::optional<std::int64_t> first_record_ns;
  std::chrono::steady_clock::time_point start;
  while (auto d = reader.next()) {
    ++result.datagrams;
    const auto destination = route(*d);
    if (!destination) {
      ++result.unrouted;
      continue;
    }
    if (!first_record_ns) {
      if (options.epoch_record_ns && options.epoch) {
        first_record_ns = *options.epoch_record_ns;
        start = std::chrono::steady_clock::time_point(
            std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                Nanoseconds(options.epoch->ns)));
      } else {
        first_record_ns = d->capture_time_ns;
        start = std::chrono::steady_clock::now();
      }
    }
    const std::int64_t offset_ns = d->capture_time_ns - *first_record_ns;
    result.recorded_span = std::max(result.recorded_span, Nanoseconds(offset_ns));
    const auto due =
        start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(Nanoseconds(
                    static_cast<std::int64_t>(static_cast<double>(offset_ns) / options.speed)));
    if (!sleep_until(due, stop)) {
      result.stopped = true;
      break;
    }
    result.max_lateness =
        std::max(result.max_lateness,
                 std::chrono::duration_cast<Nanoseconds>(std::chrono::steady_clock::now() - due));
    if (deliver(*destination, *d)) {
      ++result.delivered;
    } else {
      ++result.failed;
    }
    if (options.progress != nullptr) {
      options.progress->delivered.store(result.delivered, std::memory_order_relaxed);
      options.progress->failed.store(result.failed, std::memory_order_relaxed);
      options.progress->last_delivery_ns.store(host_now().ns, std::memory_order_relaxed);
    }
  }
  result.losses = reader.losses();
  if (options.progress != nullptr) options.progress->done.store(true, std::memory_order_release);
  return result;
}

}  // namespace

PaceResult send_pcap_paced(const std::filesystem::path& capture, std::span<const UdpRoute> routes,
                           const PaceOptions& options, const std::stop_token& stop) {
  // The receive side is unused: smallest buffers.
  io::UdpSocket socket(io::UdpSocketConfig{.bind_address = options.bind_address,
                                           .receive_buffer_bytes = 4096,
                                           .batch_size = 1,
                                           .max_datagram_bytes = 1});
  const auto route = [&](const io::UdpDatagram& d) -> std::optional<UdpRoute> {
    for (const UdpRoute& r : routes) {
      if (r.pcap_port == d.dst_port) return r;
    }
    return std::nullopt;
  };
  const auto deliver = [&](const UdpRoute& r, const io::UdpDatagram& d) {
    return socket.send_to(r.ip, r.port, d.payload);
  };
  return pace(capture, options, stop, route, deliver);
}

PaceResult push_pcap_paced(const std::filesystem::path& capture, std::span<const RingRoute> routes,
                           const PaceOptions& options, const std::stop_token& stop) {
  for (const RingRoute& r : routes) {
    if (r.ring == nullptr) throw std::invalid_argument("pcap pacer: null ring in a route");
  }
  const auto route = [&](const io::UdpDatagram& d) -> std::optional<PacketRing*> {
    for (const RingRoute& r : routes) {
      if (r.pcap_port == d.dst_port) return r.ring;
    }
    return std::nullopt;
  };
  const auto deliver = [&options](PacketRing* ring, const io::UdpDatagram& d) {
    const bool ok = ring->try_push(d.payload, host_now(), d.dst_port);
    if (ok && options.doorbell != nullptr) options.doorbell->ring();
    return ok;
  };
  return pace(capture, options, stop, route, deliver);
}

}  // namespace livod::drivers::capture
