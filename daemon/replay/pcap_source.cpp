// pcap/pcapng captures of packet LiDARs: one event per UDP datagram, stamped with its record time.

#include <fmt/core.h>

#include "daemon/replay/source_kinds.hpp"
#include "io/pcap.hpp"

namespace livod::daemon::replay {
namespace {

class PcapSource final : public ReplaySource {
 public:
  PcapSource(const std::filesystem::path& file, std::unique_ptr<drivers::LidarDecoder> decoder,
             const std::vector<std::uint16_t>& ports)
      : reader_(file), decoder_(std::move(decoder)) {
    reader_.set_port_filter(ports.empty() ? decoder_->default_ports() : ports);
  }

  std::optional<std::int64_t> peek_time() override {
    if (!pending_ && !ended_) {
      pending_ = reader_.next();
      ended_ = !pending_;
    }
    if (!pending_) return std::nullopt;
    return pending_->capture_time_ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    if (!pending_) return;
    // The payload span stays valid: the reader is not advanced before this call.
    decoder_->on_packet({pending_->payload, pending_->capture_time_ns, pending_->dst_port}, sinks);
    pending_.reset();
  }

  void finish(const drivers::DecoderSinks& sinks) override { decoder_->flush(sinks); }

  [[nodiscard]] io::InputLossLog input_losses() const override { return reader_.losses(); }

  [[nodiscard]] std::string summary() const override {
    const auto& c = decoder_->counters();
    const auto& p = reader_.stats();
    return fmt::format(
        "pcap: records {}, datagrams {}, other ports {}, not UDP {}, malformed {}, incomplete "
        "fragment sets {}; {}: packets {} (lidar {}, imu {}), scans {} ({} incomplete), points "
        "{}, late points dropped {}, sequence gaps {}, decode errors {}",
        p.records, p.udp_datagrams, p.filtered, p.non_udp, p.malformed, p.incomplete_fragments,
        decoder_->model_name(), c.packets, c.lidar_packets, c.imu_packets, c.scans,
        c.incomplete_scans, c.points, c.late_points, c.sequence_gaps, c.decode_errors);
  }

 private:
  io::PcapReader reader_;
  std::unique_ptr<drivers::LidarDecoder> decoder_;
  std::optional<io::UdpDatagram> pending_;
  bool ended_ = false;
};

}  // namespace

std::unique_ptr<ReplaySource> make_pcap_source(const std::filesystem::path& file,
                                               std::unique_ptr<drivers::LidarDecoder> decoder,
                                               const std::vector<std::uint16_t>& ports) {
  return std::make_unique<PcapSource>(file, std::move(decoder), ports);
}

}  // namespace livod::daemon::replay
