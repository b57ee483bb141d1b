#pragma once
// The interface every external IMU decoder implements, like drivers/lidar_decoder.hpp for LiDARs:
// wire data in (CAN frames, or a serial byte stream), IMU samples in SI units with the sensor's own
// time and the host receive time out, and counters for health. The same decoder object serves
// live capture (SocketCAN, termios, libusb) and replay (candump logs, serial captures), so a
// recording decodes exactly as the live sensor would.
//
// Units: gyro rad/s, accel m/s^2 (specific force), in the IMU's own frame, right-handed. Every
// unit conversion of the wire format happens inside the decoder, once.
//
// Time: stamp.sensor is the sensor's clock unwrapped to ns when the protocol carries one
// (has_sensor_clock()); otherwise it equals stamp.host (the receive time of the frame that started
// the sample) and the clock domain must run in receive_time mode. stamp.mapped is left at 0: the
// clock domain of the consumer sets it.
//
// Decoders never throw on bad input and never allocate per frame: malformed frames are counted
// and skipped.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/measurement.hpp"

namespace livod::imu {

// One CAN frame as SocketCAN or a candump log delivers it. Plain data (80 bytes): it is also the
// element of the live capture ring.
struct CanRecord {
  std::int64_t rx_time_ns = 0;  // host receive time: CLOCK_MONOTONIC live, the log time in replay
  std::uint32_t id = 0;         // 11-bit or 29-bit identifier (flags stripped)
  bool extended = false;        // 29-bit identifier
  bool fd = false;              // CAN FD frame (up to 64 data bytes)
  bool rtr = false;             // remote transmission request (no data)
  bool error = false;           // error frame: `id` holds the CAN_ERR_* class bits
  std::uint8_t len = 0;         // data bytes (0..8 classic, 0..64 FD)
  std::array<std::uint8_t, 64> data{};

  [[nodiscard]] std::span<const std::uint8_t> payload() const { return {data.data(), len}; }
};

struct ImuDecoderCounters {
  std::uint64_t frames = 0;           // CAN frames with one of the decoder's identifiers / messages
  std::uint64_t bytes = 0;            // serial decoders: bytes consumed
  std::uint64_t samples = 0;          // IMU samples emitted
  std::uint64_t malformed = 0;        // wrong length, bad field size, unknown layout: skipped
  std::uint64_t checksum_errors = 0;  // frames whose checksum failed: skipped
  std::uint64_t incomplete = 0;       // samples missing one of their frames / fields: dropped
  std::uint64_t sequence_gaps = 0;    // samples lost according to the sensor's own counter
  std::uint64_t counter_wraps = 0;    // sensor time counter wraps (unwrapped)
  std::uint64_t invalid = 0;          // samples the sensor itself flagged invalid: dropped
  std::uint64_t saturated = 0;        // samples flagged as clipped by the sensor (still emitted)
  std::uint64_t skipped_bytes = 0;    // serial decoders: bytes discarded while resynchronising
};

using ImuSink = std::function<void(const ImuSample&)>;

// CAN IMUs: SBG, Bosch MM7, YAML-described.
class CanImuDecoder {
 public:
  virtual ~CanImuDecoder() = default;
  // Feeds one frame; completed samples go to `sink`. Frames with other identifiers, remote
  // requests and error frames are ignored (the bus carries other traffic).
  virtual void on_frame(const CanRecord& frame, const ImuSink& sink) = 0;
  [[nodiscard]] virtual const ImuDecoderCounters& counters() const = 0;
  // The identifiers the decoder reads (for kernel receive filters).
  [[nodiscard]] virtual std::vector<std::uint32_t> frame_ids() const = 0;
  [[nodiscard]] virtual bool has_sensor_clock() const = 0;
  [[nodiscard]] virtual std::string model_name() const = 0;
};

// Serial / USB IMUs: a byte stream cut anywhere (reads may end mid-message).
class StreamImuDecoder {
 public:
  virtual ~StreamImuDecoder() = default;
  // Feeds the bytes of one read; `rx_time_ns` is when they arrived (a message completed by these
  // bytes takes this receive time).
  virtual void on_bytes(std::span<const std::byte> bytes, std::int64_t rx_time_ns,
                        const ImuSink& sink) = 0;
  [[nodiscard]] virtual const ImuDecoderCounters& counters() const = 0;
  [[nodiscard]] virtual bool has_sensor_clock() const = 0;
  [[nodiscard]] virtual std::string model_name() const = 0;
};

// Field-by-field sum (totals across decoders, e.g. for a summary line).
[[nodiscard]] ImuDecoderCounters sum(const ImuDecoderCounters& a, const ImuDecoderCounters& b);

// One line for reports: "samples 200, malformed 0, incomplete 0, gaps 0, ...".
[[nodiscard]] std::string format_counters(const ImuDecoderCounters& c);

// Standard gravity: the conversion of accelerations given in g.
inline constexpr double kStandardGravity = 9.80665;

}  // namespace livod::imu
