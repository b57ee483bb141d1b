#pragma once
// Live external IMUs, with the same contract as the LiDAR sources
// (drivers/capture/live_source.hpp): one capture thread per device pushing raw wire data into a
// pre-allocated ring, and a consumer side, owned by the scheduler thread, that pops the ring and
// feeds the IMU decoder (the same decoder class replay uses for candump logs and serial captures).
//
//   CAN bus --CAN_RAW socket--> capture thread --SpscRing<CanRecord>--> poll(): CanImuDecoder
//   tty / USB --termios/libusb--> capture thread --PacketRing (byte chunks)--> poll():
//   StreamImuDecoder
//
// Steady state: the capture thread never allocates, blocks only in poll()/libusb with a short
// timeout, and publishes counters with relaxed single-writer stores. A full ring drops the newest
// frame / chunk and counts it. A device that disappears (interface down, adapter unplugged) is
// reported LOST and reopened every reopen_interval (drivers/capture/device_thread.hpp); a device
// missing at construction throws livod::Error naming it.
//
// Threading contract: construct, then one consumer thread calls poll() and update_health();
// capture_counters() / device_counters() may be read from any thread; stop() or the destructor
// joins the capture thread. Samples come out with stamp.sensor and stamp.host set; stamp.mapped is
// for the consumer's clock domain (decoder().has_sensor_clock() tells which mode fits).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "core/realtime_offset.hpp"
#include "core/spsc_ring.hpp"
#include "drivers/capture/device_thread.hpp"
#include "drivers/capture/health.hpp"
#include "drivers/capture/packet_ring.hpp"
#include "drivers/imu/imu_decoder.hpp"
#include "drivers/imu/serial_port.hpp"
#include "drivers/imu/socketcan.hpp"

namespace livod::imu {

struct ImuSourceHealth {
  drivers::capture::SourceHealth
      source;  // one stream: state, rate, STALE, drops; device state, reconnects
  drivers::capture::DeviceThreadCounters device;
  ImuDecoderCounters decoder;
  CanBusCounters bus;  // CAN sources only
  std::uint64_t ring_overruns = 0;
};

// One log line (logging thread).
[[nodiscard]] std::string format_health(const ImuSourceHealth& health);

struct ImuSourceTiming {
  Nanoseconds stale_after{std::chrono::seconds(1)};  // STALE in health when silent this long
  Nanoseconds rate_window{std::chrono::seconds(5)};
};

// ---- CAN -----------------------------------------------------------------------------------

struct CanImuSourceConfig {
  std::string name;  // the sensor's name (health, thread name)
  CanSocketConfig socket;
  std::size_t ring_capacity = 4096;  // frames (~4.5 s of a 300 frames/s IMU)
  // Recording (`livod record`, outputs.record): the capture thread also copies every data frame
  // it queues into this ring (try_push: a full tap drops and counts, never blocks). May be null;
  // must outlive the source.
  SpscRing<CanRecord>* tap = nullptr;
  drivers::capture::DeviceThreadConfig thread;
  ImuSourceTiming timing;
};

class CanImuSource {
 public:
  using SocketOpener = std::function<CanSocket()>;

  // Opens the socket (throws livod::Error naming the interface) and starts the capture thread.
  // `opener` replaces CanSocket::open(config.socket) (tests). The decoder's identifiers become the
  // kernel filter unless config.socket.ids is set.
  CanImuSource(const CanImuSourceConfig& config, std::unique_ptr<CanImuDecoder> decoder,
               SocketOpener opener = {});
  ~CanImuSource();
  CanImuSource(const CanImuSource&) = delete;
  CanImuSource& operator=(const CanImuSource&) = delete;

  // Consumer thread: decodes up to max_frames queued frames; returns how many were popped.
  std::size_t poll(const ImuSink& sink, std::size_t max_frames = SIZE_MAX);
  // Consumer thread: the receive time of the oldest queued frame; nullopt when none is.
  [[nodiscard]] std::optional<HostTime> next_rx();
  // Consumer thread, at the health cadence.
  ImuSourceHealth update_health(HostTime now);

  [[nodiscard]] const CanImuDecoder& decoder() const { return *decoder_; }
  [[nodiscard]] CanBusCounters bus_counters() const;  // any thread
  [[nodiscard]] drivers::capture::DeviceThreadCounters device_counters() const;
  [[nodiscard]] const std::string& name() const { return name_; }
  void stop();

 private:
  class Link;
  std::string name_;
  std::unique_ptr<CanImuDecoder> decoder_;
  SpscRing<CanRecord> ring_;
  std::unique_ptr<Link> link_;
  drivers::capture::StreamMonitor monitor_;
  std::uint64_t popped_ = 0;
  std::unique_ptr<drivers::capture::DeviceThread> thread_;  // last: joined first
};

// ---- serial / USB --------------------------------------------------------------------------

struct SerialImuSourceConfig {
  std::string name;
  std::string path;  // "/dev/ttyUSB0", "/dev/serial/by-id/...", or "usb:VVVV:PPPP[:SERIAL]"
  int baud_rate = 115200;
  std::size_t ring_capacity = 1024;  // chunks
  std::size_t chunk_bytes = 4096;    // largest read
  // Recording: the capture thread also copies every read into this ring (slots of at least
  // chunk_bytes; try_push: a full tap drops and counts, never blocks). May be null; must outlive
  // the source.
  drivers::capture::PacketRing* tap = nullptr;
  drivers::capture::DeviceThreadConfig thread;
  ImuSourceTiming timing;
};

class SerialImuSource {
 public:
  using PortOpener = std::function<std::unique_ptr<BytePort>()>;

  // Opens the port (throws livod::Error naming it) and starts the capture thread. `opener`
  // replaces the default (SerialPort, or UsbBulkPort for a usb: path).
  SerialImuSource(const SerialImuSourceConfig& config, std::unique_ptr<StreamImuDecoder> decoder,
                  PortOpener opener = {});
  ~SerialImuSource();
  SerialImuSource(const SerialImuSource&) = delete;
  SerialImuSource& operator=(const SerialImuSource&) = delete;

  // Consumer thread: decodes up to max_chunks queued reads; returns how many were popped.
  std::size_t poll(const ImuSink& sink, std::size_t max_chunks = SIZE_MAX);
  // Consumer thread: the receive time of the oldest queued read; nullopt when none is.
  [[nodiscard]] std::optional<HostTime> next_rx();
  ImuSourceHealth update_health(HostTime now);

  [[nodiscard]] const StreamImuDecoder& decoder() const { return *decoder_; }
  [[nodiscard]] drivers::capture::DeviceThreadCounters device_counters() const;
  [[nodiscard]] drivers::capture::CaptureCounters capture_counters() const;
  [[nodiscard]] const std::string& name() const { return name_; }
  void stop();

 private:
  class Link;
  std::string name_;
  std::unique_ptr<StreamImuDecoder> decoder_;
  drivers::capture::PacketRing ring_;
  std::unique_ptr<Link> link_;
  drivers::capture::StreamMonitor monitor_;
  std::uint64_t popped_ = 0;
  std::unique_ptr<drivers::capture::DeviceThread> thread_;
};

}  // namespace livod::imu
