#pragma once
// One interface for everything that produces measurements, in the spirit of ouster-sdk's
// PacketSource: a recorded file (a pcap, a candump log, a ROS1 bag topic), a recording paced at
// its recorded speed (`replay --realtime`) or a live sensor (UDP sockets -> capture threads ->
// packet rings). The scheduler loop (scheduler.hpp) merges its sources on receive time and cannot
// tell them apart: it asks for the receive time of the next event that is ready, has the source
// decode that event into scans and IMU samples, and asks for health at the health cadence.
//
// Receive times are host times in ns: the kernel stamp of a live datagram, the record time of a
// recording in fast replay, the monotonic time of its release when paced. Sensor stamps are set by
// the decoders; `mapped` is left to the scheduler's clock domains.
//
// Threading: every method runs on the thread that owns the source (the scheduler thread); a live
// source's capture threads are its own business.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "drivers/capture/health.hpp"
#include "drivers/lidar_decoder.hpp"
#include "io/input_loss.hpp"

namespace livod::daemon::runtime {

// A thread of a source (a capture thread) and its heartbeat counter, readable from any thread.
struct SourceThread {
  std::string name;
  std::function<std::uint64_t()> beats;
};

class MeasurementSource {
 public:
  virtual ~MeasurementSource() = default;

  // Receive time (ns, host clock) of the next event that is ready now; nullopt when none is ready:
  // a recording at its end, a live source whose rings are empty. Reads at most one event ahead.
  // Throws livod::FormatError on a corrupt recording.
  virtual std::optional<std::int64_t> peek_time() = 0;
  // Decodes the event announced by peek_time() into `sinks` (an event may complete nothing).
  virtual void deliver(const drivers::DecoderSinks& sinks) = 0;
  // End of the stream: emits what the decoder still holds (the last, partial scan).
  virtual void finish(const drivers::DecoderSinks& sinks) = 0;
  // Counters for reports, one line ("packets 123, scans 10, decode errors 0, ...").
  [[nodiscard]] virtual std::string summary() const = 0;
  // Fraction of the recording consumed when the source can tell (bags), for the progress line.
  [[nodiscard]] virtual std::optional<double> fraction_done() const { return std::nullopt; }
  // What a recording's reader could not read: damaged stretches it skipped, messages that did not
  // decode. Complete once the source is exhausted. Live sources count their losses in health.
  [[nodiscard]] virtual io::InputLossLog input_losses() const { return {}; }
  // Remarks on how the recording was read (a bag index rebuilt by scanning, ...).
  [[nodiscard]] virtual std::vector<std::string> notes() const { return {}; }

  // True when no event will ever be ready again: a recording at its end, a live source stopped
  // and drained. A live source that is merely idle is not exhausted.
  [[nodiscard]] virtual bool exhausted() { return !peek_time(); }
  // Stops producing (live: joins the capture and control threads; the rings can still be
  // drained). Idempotent; a no-op for recordings.
  virtual void stop() {}
  // Per-stream health (rates, STALE, kernel drops, ring overruns, decoder counters, supervision)
  // for sources that have streams; nullopt for plain recordings, whose health the scheduler
  // derives from the events they deliver.
  [[nodiscard]] virtual std::optional<drivers::capture::SourceHealth> health(HostTime /*now*/) {
    return std::nullopt;
  }
  // Supervision that must run on the owning thread between deliveries (an Ouster re-init swaps
  // the decoder). Cheap when there is nothing to do.
  virtual void supervise(HostTime /*now*/) {}
  // The source's own threads and their heartbeats (capture threads: one per socket), for health
  // and the watchdog. Recordings have none.
  [[nodiscard]] virtual std::vector<SourceThread> threads() const { return {}; }
};

}  // namespace livod::daemon::runtime
