#pragma once
// Replays a pcap at its recorded pace into the live path: either as UDP datagrams (through the
// kernel, to a live source's sockets: tests, benchmarks, a sensor stand-in) or straight into the
// PacketRings a StreamConsumer drains (replay --realtime through the same rings and threads as
// live operation, without a network).
//
// Pacing: datagram i is released at start + (t_i - t_0) / speed, where t_i is its pcap record time
// and start the moment the first datagram is released; a pacer that falls behind sends at once
// (and reports its largest lateness). Sleeping uses CLOCK_MONOTONIC (std::chrono::steady_clock).

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <stop_token>
#include <string>

#include "core/time.hpp"
#include "drivers/capture/doorbell.hpp"
#include "drivers/capture/packet_ring.hpp"
#include "io/input_loss.hpp"

namespace livod::drivers::capture {

// Written by the pacer as it goes (any thread may read): health of a paced recording.
struct PaceProgress {
  std::atomic<std::uint64_t> delivered{0};
  std::atomic<std::uint64_t> failed{0};
  std::atomic<std::int64_t> last_delivery_ns{0};  // CLOCK_MONOTONIC of the latest delivery
  std::atomic<bool> done{false};                  // the capture is exhausted (or stopped)
};

struct PaceOptions {
  double speed = 1.0;  // 1 = recorded pace, 2 = twice as fast; must be > 0
  // send_pcap_paced only: the sending socket's address (loopback keeps tests off the network).
  std::string bind_address = "127.0.0.1";
  // One schedule for several pacers (replay --realtime paces every recording against one clock):
  // record time `epoch_record_ns` is due at `epoch` (CLOCK_MONOTONIC). Unset: the first routed
  // datagram is due when it is read.
  std::optional<std::int64_t> epoch_record_ns;
  std::optional<HostTime> epoch;
  PaceProgress* progress = nullptr;  // optional; must outlive the call
  Doorbell* doorbell = nullptr;      // push_pcap_paced: rung after each push (may be null)
};

struct PaceResult {
  std::uint64_t datagrams = 0;   // read from the capture
  std::uint64_t delivered = 0;   // sent (UDP) or pushed (ring)
  std::uint64_t failed = 0;      // send errors (UDP) or ring overruns (ring)
  std::uint64_t unrouted = 0;    // destination port without a route (skipped)
  Nanoseconds max_lateness{0};   // worst delay behind the schedule
  Nanoseconds recorded_span{0};  // last minus first record time
  bool stopped = false;          // the stop token fired before the end
  io::InputLossLog losses;       // damaged stretches of the capture its reader skipped
};

// pcap destination port -> where the live source listens.
struct UdpRoute {
  std::uint16_t pcap_port = 0;
  std::uint32_t ip = 0x7F000001;  // host order; 127.0.0.1 by default
  std::uint16_t port = 0;
};

// Sends every routed datagram of `capture` from one UDP socket (bound to options.bind_address on an
// ephemeral port; sends block when the socket's send buffer is full, so the sender never drops).
// Throws livod::Error if the capture or the socket cannot be opened.
PaceResult send_pcap_paced(const std::filesystem::path& capture, std::span<const UdpRoute> routes,
                           const PaceOptions& options, const std::stop_token& stop = {});

// pcap destination port -> ring.
struct RingRoute {
  std::uint16_t pcap_port = 0;
  PacketRing* ring = nullptr;
};

// Pushes every routed datagram into its ring, as a capture thread would: receive time = the
// monotonic time of the push, dst_port = the pcap's, a full ring drops and counts (the ring's
// overruns and PaceResult::failed). The caller's thread is the rings' producer.
PaceResult push_pcap_paced(const std::filesystem::path& capture, std::span<const RingRoute> routes,
                           const PaceOptions& options, const std::stop_token& stop = {});

}  // namespace livod::drivers::capture
