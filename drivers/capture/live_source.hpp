#pragma once
// A live LiDAR source: one UdpStream (socket + ring + capture thread) per UDP port the sensor
// sends to, and the StreamConsumer that decodes them with the model's LidarDecoder. Health (rate,
// STALE, drops) is computed on demand by the thread that owns the consumer.
//
//   sensor --UDP--> UdpStream: capture thread --PacketRing--> StreamConsumer (scheduler thread)
//                                                              -> LidarDecoder -> scans / IMU
//
// Sensor supervision sits beside it: LivoxSupervisor (drivers/livox/supervisor.hpp) brings Livox
// devices up and reconnects them; OusterReinitHandler (drivers/ouster/reinit.hpp) re-reads Ouster
// metadata when the sensor re-initialises.
//
// Threads: the constructor starts one capture thread per stream. consumer(), update_health() and
// flush belong to one consumer thread (the scheduler); stream(i).counters() may be read anywhere.
// stop() or the destructor joins the capture threads.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "drivers/capture/capture_thread.hpp"
#include "drivers/capture/health.hpp"
#include "drivers/capture/packet_ring.hpp"
#include "drivers/capture/stream_consumer.hpp"
#include "drivers/lidar_decoder.hpp"
#include "io/udp_socket.hpp"

namespace livod::drivers::capture {

struct UdpStreamConfig {
  std::string name;  // "lidar", "imu", "data", "position": shown in health
  // socket.max_datagram_bytes is also the ring's slot size: size it to the sensor's largest
  // datagram (Velodyne 1206 + 512, Livox <= 1362, Ouster up to ~33 KB) rounded up.
  io::UdpSocketConfig socket;
  std::size_t ring_capacity = 4096;  // packets; e.g. 4096 VLP-16 packets = 5.5 s
  CaptureThreadConfig thread;
};

// One socket + ring + capture thread.
class UdpStream {
 public:
  // Opens the socket (throws livod::Error naming the address), allocates the ring, starts the
  // capture thread.
  explicit UdpStream(const UdpStreamConfig& config);
  ~UdpStream();
  UdpStream(const UdpStream&) = delete;
  UdpStream& operator=(const UdpStream&) = delete;

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] std::uint16_t local_port() const { return thread_->local_port(); }
  [[nodiscard]] PacketRing& ring() { return *ring_; }
  [[nodiscard]] CaptureCounters counters() const { return thread_->counters(); }
  [[nodiscard]] int effective_receive_buffer_bytes() const {
    return thread_->effective_receive_buffer_bytes();
  }
  void stop() { thread_->stop(); }

 private:
  std::string name_;
  std::unique_ptr<PacketRing> ring_;
  std::unique_ptr<CaptureThread> thread_;  // after ring_: destroyed (joined) before it
};

struct LiveSourceConfig {
  std::string name;  // the sensor's name in the configuration
  std::vector<UdpStreamConfig> streams;
  Nanoseconds stale_after{1'000'000'000};  // a stream silent this long is STALE
  Nanoseconds rate_window{5'000'000'000};  // packets/s averaged over this window
};

class LiveSource {
 public:
  // Throws livod::Error if a socket cannot be opened (streams opened so far are stopped again) and
  // std::invalid_argument for no streams. A null decoder is allowed: packets are counted and
  // dropped until consumer().replace_decoder() installs one (an Ouster without metadata yet).
  LiveSource(const LiveSourceConfig& config, std::unique_ptr<LidarDecoder> decoder);
  ~LiveSource();
  LiveSource(const LiveSource&) = delete;
  LiveSource& operator=(const LiveSource&) = delete;

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] std::size_t stream_count() const { return streams_.size(); }
  [[nodiscard]] UdpStream& stream(std::size_t i) { return *streams_.at(i); }
  [[nodiscard]] const UdpStream& stream(std::size_t i) const { return *streams_.at(i); }

  // Consumer thread.
  [[nodiscard]] StreamConsumer& consumer() { return *consumer_; }
  // Consumer thread, at the health cadence: rates, STALE states, counters. Supervision fields of
  // SourceHealth (device_state, reconnects, ...) are left for the supervisor to fill in.
  SourceHealth update_health(HostTime now);

  // Stops and joins every capture thread (the consumer can still drain the rings). Idempotent.
  void stop();

 private:
  std::string name_;
  std::vector<std::unique_ptr<UdpStream>> streams_;
  std::vector<StreamMonitor> monitors_;
  std::unique_ptr<StreamConsumer> consumer_;
};

}  // namespace livod::drivers::capture
