// A sensor stand-in for the daemon benchmarks (bench/daemon_bench.sh): sends a capture's UDP
// payloads to 127.0.0.1 at their recorded pace (or `--speed` times faster), the destination port
// of each datagram kept, through drivers::capture::send_pcap_paced (the pacer the runtime tests
// use).
//
//   ./pcap_udp_sender CAPTURE.pcap [--speed S] [--repeat N]
//
// Prints what was sent and the pacer's worst lateness (a sender that fell behind its schedule
// offers a lower rate than asked for: the figure says whether a loss-free result means anything).

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "drivers/capture/pcap_pacer.hpp"
#include "io/pcap.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s CAPTURE.pcap [--speed S] [--repeat N]\n", argv[0]);
    return 2;
  }
  const std::filesystem::path capture = argv[1];
  livod::drivers::capture::PaceOptions options;
  int repeat = 1;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--speed") {
      options.speed = std::atof(argv[i + 1]);
    } else if (flag == "--repeat") {
      repeat = std::atoi(argv[i + 1]);
    } else {
      std::fprintf(stderr, "unknown option %s\n", flag.c_str());
      return 2;
    }
  }
  if (options.speed <= 0.0 || repeat < 1) {
    std::fprintf(stderr, "--speed must be > 0 and --repeat >= 1\n");
    return 2;
  }
  // Every destination port of the capture, sent to the same port on loopback.
  std::set<std::uint16_t> ports;
  {
    livod::io::PcapReader reader(capture);
    while (const auto d = reader.next()) ports.insert(d->dst_port);
  }
  std::vector<livod::drivers::capture::UdpRoute> routes;
  for (const auto p : ports) routes.push_back({p, 0x7F000001, p});

  for (int r = 0; r < repeat; ++r) {
    const auto result = livod::drivers::capture::send_pcap_paced(capture, routes, options);
    std::printf(
        "sent %llu of %llu datagrams (%llu failed) over %.1f s of recording at speed %.2f; "
        "worst lateness %.2f ms\n",
        static_cast<unsigned long long>(result.delivered),
        static_cast<unsigned long long>(result.datagrams),
        static_cast<unsigned long long>(result.failed),
        static_cast<double>(result.recorded_span.count()) * 1e-9, options.speed,
        static_cast<double>(result.max_lateness.count()) * 1e-6);
  }
  return 0;
}
