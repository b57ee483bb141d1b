#pragma once
// A Livox SDK1 LiDAR (an Avia) for the daemon's tests, on a loopback address of its own: it speaks
// the control protocol (handshake, start sampling, heartbeat ACKs) on <ip>:65000 and, while
// handshaken and sampling, sends the payloads of a recorded capture (points and IMU) at their
// recorded pace to the data port the handshake announced. Powered off (`online = false`) it goes
// silent and forgets the connection; the recording runs on meanwhile (its packets are lost, as a
// real sensor's are while its link is down), so that powered on again it must be handshaken anew.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <thread>

#include "io/udp_socket.hpp"

namespace livod::test {

class FakeAvia {
 public:
  // Starts answering at once; the recording starts with the first handshake.
  FakeAvia(std::uint32_t ip, std::filesystem::path capture);
  ~FakeAvia();
  FakeAvia(const FakeAvia&) = delete;
  FakeAvia& operator=(const FakeAvia&) = delete;

  std::atomic<bool> online{true};
  std::atomic<int> handshakes{0};
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> lost{0};  // recording packets while offline or not sampling
  std::atomic<bool> finished{false};   // the whole recording went by

  // A loopback address of its own (127.76.x.y from the pid): parallel tests never share the
  // LiDAR command port 65000.
  static std::uint32_t loopback_ip();

 private:
  void control(const std::stop_token& stop);
  void stream(const std::stop_token& stop);

  std::uint32_t ip_;
  std::filesystem::path capture_;
  io::UdpSocket control_socket_;
  io::UdpSocket data_socket_;
  std::mutex mutex_;
  std::uint32_t host_ip_ = 0;    // guarded by mutex_
  std::uint16_t data_port_ = 0;  // guarded by mutex_
  bool sampling_ = false;        // guarded by mutex_
  std::atomic<bool> started_{false};
  std::jthread control_thread_;  // last two: started once the rest is ready
  std::jthread stream_thread_;
};

}  // namespace livod::test
