// The highest loss-free packet rate of the live UDP path on loopback: a sender thread at
// increasing rates (sendmmsg batches) -> kernel socket -> capture thread (recvmmsg batches) ->
// PacketRing -> consumer thread (checks each packet's sequence number; decoding is measured by the
// *_decode_bench programs). For each payload size (1206 B = a Velodyne data packet, 8192 B = an
// Ouster-class datagram) and each offered rate, a trial runs for --seconds and reports what
// arrived, the kernel drops (SO_RXQ_OVFL), the ring overruns and the sender's achieved rate. The
// last line per size is the highest rate with zero loss, and whether the sender (not the capture
// path) was the limit.
//
//   ./udp_live_bench [--seconds S] [--ring N] [--rcvbuf BYTES] [--rt PRIO] [--cpu-capture C]
//
// A small program rather than a Google Benchmark: a trial is a multi-thread steady state with a
// pass/fail outcome (loss), not a timed loop. Sender, capture thread and consumer compete for the
// machine's cores; on loopback the kernel's receive path also runs in the sender's context.

#include <benchmark/benchmark.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "drivers/capture/live_source.hpp"
#include "io/udp_socket.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using livod::drivers::capture::CaptureCounters;
using livod::drivers::capture::RawPacket;
using livod::drivers::capture::UdpStream;
using livod::drivers::capture::UdpStreamConfig;

constexpr std::uint32_t kLoopback = 0x7F000001;

struct Options {
  double seconds = 1.0;
  std::size_t ring = 4096;
  int rcvbuf = 8 << 20;
  int rt_priority = 0;  // 0 = normal scheduling
  int capture_cpu = -1;
};

struct Trial {
  double offered_pps = 0;  // 0 = as fast as the sender can
  double achieved_pps = 0;
  std::uint64_t sent = 0;
  std::uint64_t consumed = 0;
  std::uint64_t kernel_drops = 0;
  std::uint64_t ring_overruns = 0;
  std::uint64_t out_of_sequence = 0;  // sequence jumps seen by the consumer
  const char* rt = "";
  [[nodiscard]] bool lossless() const {
    return sent > 0 && consumed == sent && kernel_drops == 0 && ring_overruns == 0 &&
           out_of_sequence == 0;
  }
};

// A connected UDP socket sending numbered datagrams with sendmmsg (the first 8 bytes of each
// payload carry its sequence number).
class Sender {
 public:
  static constexpr std::uint64_t kBatch = 32;

  Sender(std::uint16_t port, std::size_t payload_bytes)
      : fd_(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0)),
        payloads_(kBatch, std::vector<std::byte>(payload_bytes)) {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(kLoopback);
    if (fd_ < 0 || ::connect(fd_, reinterpret_cast<sockaddr*>(&to), sizeof(to)) != 0) {
      std::perror("sender socket");
      std::exit(1);
    }
    for (auto& p : payloads_) {
      for (std::size_t i = 0; i < p.size(); ++i) p[i] = static_cast<std::byte>(i * 7);
    }
  }
  ~Sender() { ::close(fd_); }
  Sender(const Sender&) = delete;
  Sender& operator=(const Sender&) = delete;

  // Sends up to `count` (<= kBatch) datagrams numbered from `first`; returns how many went out.
  std::uint64_t send(std::uint64_t first, std::uint64_t count) {
    std::array<iovec, kBatch> iov{};
    std::array<mmsghdr, kBatch> msgs{};
    for (std::uint64_t i = 0; i < count; ++i) {
      const std::uint64_t sequence = first + i;
      std::memcpy(payloads_[i].data(), &sequence, sizeof(sequence));
      iov[i] = iovec{payloads_[i].data(), payloads_[i].size()};
      msgs[i].msg_hdr.msg_iov = &iov[i];
      msgs[i].msg_hdr.msg_iovlen = 1;
    }
    const int n = ::sendmmsg(fd_, msgs.data(), static_cast<unsigned>(count), 0);
    return n > 0 ? static_cast<std::uint64_t>(n) : 0;
  }

 private:
  int fd_;
  std::vector<std::vector<std::byte>> payloads_;
};

Trial run_trial(std::size_t payload_bytes, double rate_pps, const Options& o) {
  UdpStreamConfig config;
  config.name = "bench";
  config.socket.bind_address = "127.0.0.1";
  config.socket.max_datagram_bytes = payload_bytes;
  config.socket.receive_buffer_bytes = o.rcvbuf;
  config.ring_capacity = o.ring;
  config.thread.thread_name = "cap-bench";
  if (o.rt_priority > 0) config.thread.realtime_priority = o.rt_priority;
  if (o.capture_cpu >= 0) config.thread.cpu = o.capture_cpu;
  UdpStream stream(config);

  std::atomic<bool> stop_consumer{false};
  std::atomic<std::uint64_t> consumed{0};
  std::atomic<std::uint64_t> out_of_sequence{0};
  std::thread consumer([&] {
    std::uint64_t n = 0;
    std::uint64_t expected_sequence = 0;
    std::uint64_t jumps = 0;
    while (!stop_consumer.load(std::memory_order_acquire)) {
      const RawPacket* p = stream.ring().front();
      if (p == nullptr) {
        std::this_thread::sleep_for(std::chrono::microseconds(100));
        continue;
      }
      std::uint64_t sequence = 0;
      std::memcpy(&sequence, p->payload.data(), sizeof(sequence));
      if (sequence != expected_sequence) ++jumps;  // a loss upstream (or reordering)
      expected_sequence = sequence + 1;
      stream.ring().pop();
      consumed.store(++n, std::memory_order_relaxed);
      out_of_sequence.store(jumps, std::memory_order_relaxed);
    }
  });

  Sender tx(stream.local_port(), payload_bytes);
  std::uint64_t sent = 0;
  const auto start = Clock::now();
  const auto end =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.seconds));
  if (rate_pps <= 0) {
    while (Clock::now() < end) sent += tx.send(sent, Sender::kBatch);
  } else {
    // 1 ms ticks: each tick sends what the schedule owes (a sender that fell behind catches up).
    auto tick = start;
    while (tick < end) {
      tick += std::chrono::milliseconds(1);
      std::this_thread::sleep_until(tick);
      const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      const auto due = static_cast<std::uint64_t>(std::min(elapsed, o.seconds) * rate_pps);
      while (sent < due) sent += tx.send(sent, std::min<std::uint64_t>(due - sent, Sender::kBatch));
    }
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();

  // Let the path drain (bounded), then read the counters.
  const auto drain_end = Clock::now() + std::chrono::seconds(2);
  while (Clock::now() < drain_end) {
    const CaptureCounters c = stream.counters();
    if (c.datagrams + c.kernel_drops >= sent && consumed.load() >= c.pushed) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  stream.stop();
  stop_consumer.store(true, std::memory_order_release);
  consumer.join();

  const CaptureCounters c = stream.counters();
  Trial t;
  t.out_of_sequence = out_of_sequence.load();
  t.offered_pps = rate_pps;
  t.achieved_pps = static_cast<double>(sent) / elapsed;
  t.sent = sent;
  t.consumed = consumed.load();
  // A drop at the very end is only reported by the kernel with a later datagram: count what never
  // arrived as a drop as well.
  t.kernel_drops = std::max<std::uint64_t>(c.kernel_drops, sent - std::min(sent, c.datagrams));
  t.ring_overruns = c.ring_overruns;
  t.rt = livod::drivers::capture::to_string(c.priority);
  return t;
}

void print(std::size_t payload_bytes, const Trial& t) {
  std::printf(
      "%6zu B  offered %9s  achieved %9.0f pkt/s %8.1f Mbit/s  sent %9llu  lost %7llu "
      "(kernel %llu, ring %llu, seq jumps %llu)  %s\n",
      payload_bytes,
      t.offered_pps > 0 ? std::to_string(static_cast<long long>(t.offered_pps)).c_str() : "max",
      t.achieved_pps, t.achieved_pps * static_cast<double>(payload_bytes) * 8e-6,
      static_cast<unsigned long long>(t.sent),
      static_cast<unsigned long long>(t.sent - std::min(t.sent, t.consumed)),
      static_cast<unsigned long long>(t.kernel_drops),
      static_cast<unsigned long long>(t.ring_overruns),
      static_cast<unsigned long long>(t.out_of_sequence), t.lossless() ? "ok" : "LOSS");
  std::fflush(stdout);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    const char* value = argv[i + 1];
    if (key == "--seconds") {
      o.seconds = std::atof(value);
    } else if (key == "--ring") {
      o.ring = static_cast<std::size_t>(std::atol(value));
    } else if (key == "--rcvbuf") {
      o.rcvbuf = std::atoi(value);
    } else if (key == "--rt") {
      o.rt_priority = std::atoi(value);
    } else if (key == "--cpu-capture") {
      o.capture_cpu = std::atoi(value);
    } else {
      std::fprintf(stderr, "unknown option %s\n", key.c_str());
      std::exit(2);
    }
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::printf(
      "live UDP path on loopback: %.1f s per trial, ring %zu, SO_RCVBUF request %d, "
      "SCHED_FIFO %s, %u hardware threads\n",
      o.seconds, o.ring, o.rcvbuf,
      o.rt_priority > 0 ? std::to_string(o.rt_priority).c_str() : "off",
      std::thread::hardware_concurrency());
  const std::vector<double> rates{10'000,  20'000,  40'000,  80'000,  120'000,
                                  160'000, 240'000, 320'000, 480'000, 0};
  for (const std::size_t payload_bytes : {std::size_t{1206}, std::size_t{8192}}) {
    Trial best;
    bool sender_limited = false;
    for (const double rate : rates) {
      Trial t = run_trial(payload_bytes, rate, o);
      print(payload_bytes, t);
      if (t.lossless() && t.achieved_pps > best.achieved_pps) best = t;
      if (!t.lossless()) break;  // the path's limit is below this offer
      // The sender cannot keep up with the offer: try flat out once and stop.
      if (rate <= 0 || t.achieved_pps < 0.9 * rate) {
        if (rate > 0) {
          t = run_trial(payload_bytes, 0, o);
          print(payload_bytes, t);
          if (t.lossless() && t.achieved_pps > best.achieved_pps) best = t;
        }
        sender_limited = t.lossless();
        break;
      }
    }
    std::printf("%6zu B  highest loss-free rate: %.0f pkt/s = %.1f Mbit/s%s (capture RT: %s)\n\n",
                payload_bytes, best.achieved_pps,
                best.achieved_pps * static_cast<double>(payload_bytes) * 8e-6,
                sender_limited ? " (sender-limited: the capture path lost nothing at the "
                                 "sender's maximum)"
                               : "",
                best.rt);
  }
  return 0;
}
