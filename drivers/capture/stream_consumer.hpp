#pragma once
// The consumer side of a LiDAR's capture rings: pops raw packets (oldest receive time first across
// the sensor's rings, e.g. Ouster lidar + IMU ports, Velodyne data + position ports) and feeds
// them to the model's LidarDecoder. The daemon's scheduler thread owns one per LiDAR and calls
// poll() in its loop; replay in --realtime mode uses the same class behind the pcap pacer.
//
// Single-threaded: every method runs on the consumer thread (the rings' consumer side).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/time.hpp"
#include "drivers/capture/packet_ring.hpp"
#include "drivers/lidar_decoder.hpp"

namespace livod::drivers::capture {

struct ConsumerCounters {
  std::uint64_t packets = 0;            // popped from the rings and decoded
  std::uint64_t truncated_skipped = 0;  // popped but not decoded: cut by the slot size
  // Popped but not decoded: no decoder yet (an Ouster whose metadata is still being fetched).
  std::uint64_t without_decoder = 0;
  std::uint64_t decoder_replacements = 0;
};

class StreamConsumer {
 public:
  // `rings` must outlive the consumer. Throws std::invalid_argument for a null ring. A null
  // decoder is allowed: packets are then popped and counted (without_decoder) until
  // replace_decoder() installs one, so that the rings never fill while a decoder is pending.
  StreamConsumer(std::unique_ptr<LidarDecoder> decoder, std::vector<PacketRing*> rings);

  // Decodes up to `max_packets` queued packets; scans and IMU samples go to `sinks`. Returns the
  // number of packets popped (0: every ring was empty).
  std::size_t poll(const DecoderSinks& sinks, std::size_t max_packets = SIZE_MAX);

  // Receive time of the oldest queued packet over the sensor's rings (what poll() pops next);
  // nullopt when every ring is empty.
  [[nodiscard]] std::optional<HostTime> next_rx();

  // Emits the scan under construction (end of stream).
  void flush(const DecoderSinks& sinks) {
    if (decoder_) decoder_->flush(sinks);
  }

  [[nodiscard]] bool has_decoder() const { return decoder_ != nullptr; }
  // Precondition: has_decoder().
  [[nodiscard]] LidarDecoder& decoder() { return *decoder_; }
  [[nodiscard]] const LidarDecoder& decoder() const { return *decoder_; }

  // Installs a new decoder (e.g. an Ouster sensor re-initialised with new metadata). The partial
  // scan of the old decoder is discarded; its counters are kept in decoder_counters().
  void replace_decoder(std::unique_ptr<LidarDecoder> decoder);

  // Totals over every decoder this consumer has used.
  [[nodiscard]] DecoderCounters decoder_counters() const;
  [[nodiscard]] const ConsumerCounters& counters() const { return counters_; }
  // Receive time of the newest decoded packet.
  [[nodiscard]] std::optional<HostTime> last_rx() const { return last_rx_; }

 private:
  std::unique_ptr<LidarDecoder> decoder_;
  std::vector<PacketRing*> rings_;
  DecoderCounters retired_;  // sums of the replaced decoders
  ConsumerCounters counters_;
  std::optional<HostTime> last_rx_;
};

// Field-by-field sum (totals over several decoders).
[[nodiscard]] DecoderCounters sum(const DecoderCounters& a, const DecoderCounters& b);

}  // namespace livod::drivers::capture
