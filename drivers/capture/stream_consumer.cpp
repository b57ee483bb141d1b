#include "drivers/capture/stream_consumer.hpp"

#include <stdexcept>
#include <utility>

namespace livod::drivers::capture {

DecoderCounters sum(const DecoderCounters& a, const DecoderCounters& b) {
  DecoderCounters s;
  s.packets = a.packets + b.packets;
  s.lidar_packets = a.lidar_packets + b.lidar_packets;
  s.imu_packets = a.imu_packets + b.imu_packets;
  s.aux_packets = a.aux_packets + b.aux_packets;
  s.decode_errors = a.decode_errors + b.decode_errors;
  s.sequence_gaps = a.sequence_gaps + b.sequence_gaps;
  s.scans = a.scans + b.scans;
  s.incomplete_scans = a.incomplete_scans + b.incomplete_scans;
  s.points = a.points + b.points;
  return s;
}

StreamConsumer::StreamConsumer(std::unique_ptr<LidarDecoder> decoder,
                               std::vector<PacketRing*> rings)
    : decoder_(std::move(decoder)), rings_(std::move(rings)) {
  for (const PacketRing* ring : rings_) {
    if (ring == nullptr) throw std::invalid_argument("StreamConsumer: null ring");
  }
}

std::size_t StreamConsumer::poll(const DecoderSinks& sinks, std::size_t max_packets) {
  std::size_t done = 0;
  while (done < max_packets) {
    // Oldest receive time first, so that packets of a sensor's several ports reach the decoder in
    // arrival order (e.g. a Velodyne position packet between two data packets).
    PacketRing* oldest_ring = nullptr;
    const RawPacket* oldest = nullptr;
    for (PacketRing* ring : rings_) {
      const RawPacket* p = ring->front();
      if (p != nullptr && (oldest == nullptr || p->rx < oldest->rx)) {
        oldest = p;
        oldest_ring = ring;
      }
    }
    if (oldest == nullptr) break;
    if (oldest->truncated) {
      // A cut datagram would only be a decode error with a misleading cause; count it here.
      ++counters_.truncated_skipped;
    } else if (!decoder_) {
      ++counters_.without_decoder;
    } else {
      decoder_->on_packet(PacketView{oldest->payload, oldest->rx.ns, oldest->dst_port}, sinks);
    }
    last_rx_ = oldest->rx;
    oldest_ring->pop();
    ++counters_.packets;
    ++done;
  }
  return done;
}

std::optional<HostTime> StreamConsumer::next_rx() {
  std::optional<HostTime> oldest;
  for (PacketRing* ring : rings_) {
    const RawPacket* p = ring->front();
    if (p != nullptr && (!oldest || p->rx < *oldest)) oldest = p->rx;
  }
  return oldest;
}

void StreamConsumer::replace_decoder(std::unique_ptr<LidarDecoder> decoder) {
  if (!decoder) throw std::invalid_argument("StreamConsumer: no decoder");
  if (decoder_) retired_ = sum(retired_, decoder_->counters());
  decoder_ = std::move(decoder);
  ++counters_.decoder_replacements;
}

DecoderCounters StreamConsumer::decoder_counters() const {
  return decoder_ ? sum(retired_, decoder_->counters()) : retired_;
}

}  // namespace livod::drivers::capture
