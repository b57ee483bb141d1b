#pragma once
// Recorded streams for replay. A source reads one sensor's recording one event at a time (a UDP
// datagram of a pcap, a frame of a candump log, a message of a ROS1 bag), tells the receive time
// of its next event (pcap record time, candump log time, bag record time: the host clock of the
// recording) and, when the replay's merge picks it, decodes that event into scans and IMU
// samples with their sensor and host stamps (`mapped` is left to the clock domain).
//
// Memory is bounded by construction: a source holds at most one undecoded event and its decoder's
// scan under construction; files are streamed, never loaded whole.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "drivers/lidar_decoder.hpp"
#include "io/input_loss.hpp"

namespace livod::daemon::replay {

class ReplaySource {
 public:
  virtual ~ReplaySource() = default;
  // Receive time (ns, the recording's host clock) of the next event; nullopt at the end. Reads at
  // most one event ahead. Throws livod::FormatError on a corrupt file.
  virtual std::optional<std::int64_t> peek_time() = 0;
  // Decodes the event announced by peek_time() into `sinks` (a packet may complete nothing).
  virtual void deliver(const drivers::DecoderSinks& sinks) = 0;
  // End of the recording: emits what the decoder still holds (the last, partial scan).
  virtual void finish(const drivers::DecoderSinks& sinks) = 0;
  // Counters for the report, one line ("packets 123, scans 10, decode errors 0, ...").
  [[nodiscard]] virtual std::string summary() const = 0;
  // Fraction of the recording consumed when the source can tell (bags), for the progress line.
  [[nodiscard]] virtual std::optional<double> fraction_done() const { return std::nullopt; }
  // What the source could not read of its recording: damaged stretches its reader skipped,
  // messages that did not decode. Complete once peek_time() has returned nullopt.
  [[nodiscard]] virtual io::InputLossLog input_losses() const { return {}; }
  // Remarks on how the recording was read (a bag index rebuilt by scanning, ...).
  [[nodiscard]] virtual std::vector<std::string> notes() const { return {}; }
};

// The source for one sensor's recording. `ports`: the UDP destination ports to keep from a pcap
// (empty: the decoder's defaults). Throws livod::Error naming the sensor when the recording
// cannot be opened or when this driver cannot be replayed from this format (e.g. a custom CAN
// decoder, a bag topic of an unexpected message type).
std::unique_ptr<ReplaySource> make_source(const SensorConfig& sensor,
                                          const ReplaySourceConfig& replay,
                                          const std::vector<std::uint16_t>& ports);

}  // namespace livod::daemon::replay
