#pragma once
// The interface every LiDAR family implements: UDP payloads in (live or from a capture), assembled
// scans and IMU samples out. Decoding itself is a pure function over bytes inside each family;
// this stateful wrapper adds scan assembly, sequence-gap detection and counters.
//
// INTERFACE CONTRACT: shared by drivers/velodyne, drivers/ouster, drivers/livox, the `decode`
// subcommand, the live UDP sources and replay.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/measurement.hpp"

namespace livod {
struct ImageFrame;  // core/image.hpp (kept out of this header: it pulls in OpenCV)
}  // namespace livod

namespace livod::drivers {

// Counters a decoder keeps; read by health reporting and printed by `livod decode`.
struct DecoderCounters {
  std::uint64_t packets = 0;           // payloads handed to on_packet()
  std::uint64_t lidar_packets = 0;     // decoded point packets
  std::uint64_t imu_packets = 0;       // decoded IMU packets
  std::uint64_t aux_packets = 0;       // other recognised packets (position/telemetry/status)
  std::uint64_t decode_errors = 0;     // malformed (bad length, bad CRC, bad header): skipped
  std::uint64_t sequence_gaps = 0;     // packets missing according to the sensor's own counters
  std::uint64_t scans = 0;             // scans emitted (including partial ones)
  std::uint64_t incomplete_scans = 0;  // scans emitted or dropped with missing packets/columns
  std::uint64_t points = 0;            // points emitted (valid ones)
  // Points that arrived after the scan they belong to was closed (a packet delayed or reordered
  // past the next scan's first packet): dropped, so that a late packet neither splits the scan
  // under construction nor becomes a scan of its own.
  std::uint64_t late_points = 0;
  // The sensor clock jumped (time sync gained or lost, timestamp type changed, reset): a clock
  // event, not a loss. The timeline restarts at the new time and no packets are counted missing
  // across the jump (the clock domain downstream sees the step and restarts its estimate).
  std::uint64_t clock_jumps = 0;
};

// Callbacks receive references valid only during the call (the decoder reuses its buffers).
struct DecoderSinks {
  std::function<void(const LidarScan&)> on_scan;
  std::function<void(const ImuSample&)> on_imu;
  // Camera frames (image sources): stamp.sensor / stamp.host, exposure and stamp_marks set,
  // stamp.mapped left to the clock domain. The frame owns its pixels (a sink may keep them).
  std::function<void(const ImageFrame&)> on_image;
};

// One received UDP payload. host_time_ns is the receive time (kernel stamp live, the pcap record
// time in replay); it becomes Stamp::host of what the packet produces.
struct PacketView {
  std::span<const std::byte> payload;
  std::int64_t host_time_ns = 0;
  std::uint16_t dst_port = 0;
};

class LidarDecoder {
 public:
  virtual ~LidarDecoder() = default;
  // Decodes one payload; completed scans and IMU samples go to `sinks`. Never throws on bad
  // input: malformed payloads are counted in decode_errors and skipped.
  virtual void on_packet(const PacketView& packet, const DecoderSinks& sinks) = 0;
  // Emits the scan under construction, if any (end of capture).
  virtual void flush(const DecoderSinks& sinks) = 0;
  [[nodiscard]] virtual const DecoderCounters& counters() const = 0;
  // UDP ports this sensor sends to by default (data first).
  [[nodiscard]] virtual std::vector<std::uint16_t> default_ports() const = 0;
  [[nodiscard]] virtual std::string model_name() const = 0;
};

}  // namespace livod::drivers
