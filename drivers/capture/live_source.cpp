#include "drivers/capture/live_source.hpp"

#include <stdexcept>
#include <utility>

namespace livod::drivers::capture {

UdpStream::UdpStream(const UdpStreamConfig& config)
    : name_(config.name),
      ring_(std::make_unique<PacketRing>(config.ring_capacity, config.socket.max_datagram_bytes)) {
  io::UdpSocket socket(config.socket);
  thread_ = std::make_unique<CaptureThread>(std::move(socket), *ring_, config.thread);
}

UdpStream::~UdpStream() {
  // Explicit: the ring must not go away while the capture thread may still push.
  thread_.reset();
}

LiveSource::LiveSource(const LiveSourceConfig& config, std::unique_ptr<LidarDecoder> decoder)
    : name_(config.name) {
  if (config.streams.empty()) throw std::invalid_argument("LiveSource '" + name_ + "': no streams");
  std::vector<PacketRing*> rings;
  // If a later socket fails to open, the streams already built are destroyed (and joined) by
  // streams_'s destructor during stack unwinding.
  for (const UdpStreamConfig& s : config.streams) {
    streams_.push_back(std::make_unique<UdpStream>(s));
    monitors_.emplace_back(s.name, config.stale_after, config.rate_window);
    rings.push_back(&streams_.back()->ring());
  }
  consumer_ = std::make_unique<StreamConsumer>(std::move(decoder), std::move(rings));
}

LiveSource::~LiveSource() {
  stop();
}

void LiveSource::stop() {
  for (auto& s : streams_) s->stop();
}

SourceHealth LiveSource::update_health(HostTime now) {
  SourceHealth h;
  h.name = name_;
  h.streams.reserve(streams_.size());
  for (std::size_t i = 0; i < streams_.size(); ++i) {
    h.streams.push_back(monitors_[i].update(now, streams_[i]->counters()));
  }
  h.decoder = consumer_->decoder_counters();
  h.consumer = consumer_->counters();
  return h;
}

}  // namespace livod::drivers::capture
