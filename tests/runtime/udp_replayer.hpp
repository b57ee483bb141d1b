#pragma once
// A sensor stand-in for the daemon's tests: sends a pcap's UDP payloads to loopback ports at their
// recorded pace, with the faults a real link has: a silent window (a cable pulled: the packets of
// that stretch of the recording are never sent, the sensor's clock runs on) and malformed
// datagrams between the real ones. Several captures (a rig of several LiDARs, one pcap each) are
// sent on one timeline, each datagram at its capture time, as the sensors sent them.

#include <cstdint>
#include <filesystem>
#include <stop_token>
#include <vector>

namespace livod::test {

struct UdpRoute {
  std::uint16_t pcap_port = 0;   // destination port in the capture
  std::uint16_t local_port = 0;  // where the daemon listens on 127.0.0.1
};

struct ReplayFaults {
  double silent_from_s = -1.0;  // recording time (s after the first packet) the link goes silent
  double silent_to_s = -1.0;
  int malformed_every = 0;  // after every n-th real datagram, one malformed datagram; 0: none
  std::uint64_t seed = 1;
};

struct SenderResult {
  std::uint64_t sent = 0;
  std::uint64_t silenced = 0;  // not sent: inside the silent window
  std::uint64_t malformed = 0;
  double span_s = 0.0;
};

SenderResult send_capture(const std::filesystem::path& pcap, const std::vector<UdpRoute>& routes,
                          const ReplayFaults& faults = {}, const std::stop_token& stop = {});

// One sensor's capture among several: its routes and faults are its own (the pcaps of two
// identical LiDARs have the same destination ports); the silent window is on the common timeline
// (s after the earliest first packet of all captures).
struct CaptureStream {
  std::filesystem::path pcap;
  std::vector<UdpRoute> routes;
  ReplayFaults faults;
};

// Sends every capture's datagrams in capture-time order from one thread; one result per capture.
std::vector<SenderResult> send_captures(const std::vector<CaptureStream>& captures,
                                        const std::stop_token& stop = {});

}  // namespace livod::test
