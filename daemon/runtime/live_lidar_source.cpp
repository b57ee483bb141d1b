#include "daemon/runtime/live_lidar_source.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "core/error.hpp"
#include "daemon/config/sensor_models.hpp"
#include "daemon/record/recorder.hpp"
#include "daemon/replay/decoder_factory.hpp"
#include "drivers/capture/live_source.hpp"
#include "drivers/livox/supervisor.hpp"
#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/ouster_decoder.hpp"
#include "drivers/ouster/reinit.hpp"
#include "io/udp_socket.hpp"

namespace livod::daemon::runtime {
namespace {

constexpr int kOusterHttpPort = 80;

std::string label(const SensorConfig& s) {
  return "sensor '" + s.name + "' (" + std::string(enum_name(s.driver)) + " " + s.model + ")";
}

// The host address the sensor reaches us at: the configured bind address, else the local
// address of the route to the sensor (a connected UDP socket sends nothing).
std::uint32_t host_ip_for(const UdpSourceConfig& udp, const std::string& what) {
  if (!udp.bind_address.empty() && udp.bind_address != "0.0.0.0") {
    return io::parse_ipv4(udp.bind_address);
  }
  if (udp.sensor_address.empty()) return 0;
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw Error(what + ": socket: " + std::strerror(errno));
  sockaddr_in sensor{};
  sensor.sin_family = AF_INET;
  sensor.sin_port = htons(9);
  sensor.sin_addr.s_addr = htonl(io::parse_ipv4(udp.sensor_address));
  sockaddr_in local{};
  socklen_t len = sizeof(local);
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&sensor), sizeof(sensor)) == 0 &&
                  ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len) == 0;
  const int err = errno;
  ::close(fd);
  if (!ok) {
    throw Error(what + ": no route to the sensor at " + udp.sensor_address + ": " +
                std::strerror(err));
  }
  return ntohl(local.sin_addr.s_addr);
}

class LiveLidar final : public LiveLidarSource {
 public:
  LiveLidar(const SensorConfig& sensor, const LiveOptions& options) : name_(sensor.name) {
    const auto* udp = std::get_if<UdpSourceConfig>(&sensor.source);
    if (udp == nullptr) throw Error(label(sensor) + ": live operation needs a source.udp section");
    const std::string what = label(sensor);

    // Ring slot sizes are the family's largest datagrams (drivers/lidar_family.hpp).
    const drivers::LidarFamily* family = lidar_family(sensor.driver);
    if (family == nullptr) throw Error(what + " is not a packet LiDAR");
    std::size_t lidar_slot = family->lidar_datagram_bytes;
    std::unique_ptr<drivers::LidarDecoder> decoder;
    if (sensor.driver != Driver::ouster || !sensor.metadata.empty()) {
      decoder = replay::make_lidar_decoder(sensor);
      // An Ouster's point packets have the size its metadata's profile gives.
      if (const auto* o = dynamic_cast<const drivers::ouster::OusterDecoder*>(decoder.get())) {
        lidar_slot = o->packet_format().lidar_packet_size;
      }
    } else if (udp->sensor_address.empty()) {
      throw Error(what + ": without a metadata file the metadata is fetched from the sensor: " +
                  "set source.udp.sensor_address");
    }

    // The destination address a recording writes into its frames: the multicast group, else the
    // host address the sensor sends to when it can be told (0.0.0.0 otherwise).
    std::uint32_t record_dst_ip = 0;
    if (options.recorder != nullptr) {
      try {
        record_dst_ip = !udp->multicast_group.empty() ? io::parse_ipv4(udp->multicast_group)
                                                      : host_ip_for(*udp, what);
      } catch (const Error&) {
        record_dst_ip = 0;
      }
    }

    drivers::capture::LiveSourceConfig lc;
    lc.name = sensor.name;
    lc.stale_after = options.stale_after;
    const auto add_stream = [&](const std::string& name, std::uint16_t port, std::size_t slot) {
      drivers::capture::UdpStreamConfig s;
      s.name = name;
      s.socket.bind_address = udp->bind_address;
      s.socket.port = options.ephemeral_ports ? 0 : port;
      s.socket.multicast_group = udp->multicast_group;
      s.socket.receive_buffer_bytes = udp->socket_buffer_bytes;
      s.socket.max_datagram_bytes = slot;
      s.ring_capacity = sensor.ring_capacity > 0 ? static_cast<std::size_t>(sensor.ring_capacity)
                                                 : s.ring_capacity;
      s.thread.thread_name = (sensor.name + "." + name).substr(0, 15);
      s.thread.realtime_priority = options.capture_priority;
      s.thread.cpu = options.capture_cpu;
      s.thread.reported_port = port;
      s.thread.doorbell = options.doorbell;
      if (options.recorder != nullptr) {
        s.thread.tap =
            &options.recorder->add_packet_stream({sensor.name, name, slot, record_dst_ip});
      }
      lc.streams.push_back(std::move(s));
      stream_names_.push_back(name);
    };
    const UdpPorts& ports = udp->ports;
    add_stream("lidar", ports.lidar, lidar_slot);
    const bool imu_port = ports.imu != 0 && ports.imu != ports.lidar && sensor.imu.enabled;
    if (imu_port) {
      add_stream("imu", ports.imu, family->aux_datagram_bytes);
    }
    if (ports.position != 0) add_stream("position", ports.position, family->aux_datagram_bytes);
    live_ = std::make_unique<drivers::capture::LiveSource>(lc, std::move(decoder));

    if (sensor.driver == Driver::livox_sdk1 || sensor.driver == Driver::livox_sdk2) {
      livox::LivoxSupervisorConfig sc;
      sc.device.protocol =
          sensor.driver == Driver::livox_sdk1 ? livox::Protocol::kSdk1 : livox::Protocol::kSdk2;
      sc.device.host_ip = host_ip_for(*udp, what);
      if (sc.device.host_ip == 0) {
        throw Error(what + ": the LiDAR must be told where to send: set source.udp." +
                    "sensor_address (the host address is then the one routing to it) or a " +
                    "bind_address other than 0.0.0.0");
      }
      if (!udp->sensor_address.empty()) sc.device.lidar_ip = io::parse_ipv4(udp->sensor_address);
      sc.device.host_cmd_port = options.ephemeral_ports ? 0 : ports.command;
      sc.device.host_state_port = 0;  // the command socket takes the status pushes
      sc.device.host_data_port = live_->stream(0).local_port();
      sc.device.host_imu_port =
          imu_port ? live_->stream(1).local_port() : live_->stream(0).local_port();
      sc.bind_address = udp->bind_address;
      // SDK1 LiDARs announce themselves on 55000; with a known address there is nothing to hear.
      if (sc.device.protocol == livox::Protocol::kSdk1 && !sc.device.lidar_ip) {
        sc.broadcast_port = static_cast<std::uint16_t>(55000);
      }
      std::vector<const drivers::capture::UdpStream*> data;
      for (std::size_t i = 0; i < live_->stream_count(); ++i) data.push_back(&live_->stream(i));
      livox_ = std::make_unique<livox::LivoxSupervisor>(sc, std::move(data));
    }
    if (sensor.driver == Driver::ouster && !udp->sensor_address.empty()) {
      drivers::ouster::OusterMetadataFetcherConfig fc;
      fc.host = udp->sensor_address;
      fc.port = kOusterHttpPort;
      if (options.recorder != nullptr && sensor.metadata.empty()) {
        // The recording replays only with the metadata: keep what the sensor serves.
        record::Recorder* recorder = options.recorder;
        recorder->expect_metadata(sensor.name);
        fc.on_fetched = [recorder, name = sensor.name](const std::string& json) {
          recorder->save_metadata(name, json);
        };
      }
      fetcher_ = std::make_unique<drivers::ouster::OusterMetadataFetcher>(fc);
      reinit_ = std::make_unique<drivers::ouster::OusterReinitHandler>(
          *fetcher_, drivers::ouster::OusterDecoderOptions{});
    }
  }

  ~LiveLidar() override { stop(); }

  std::optional<std::int64_t> peek_time() override {
    const auto rx = live_->consumer().next_rx();
    if (!rx) return std::nullopt;
    return rx->ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override { live_->consumer().poll(sinks, 1); }

  void finish(const drivers::DecoderSinks& sinks) override { live_->consumer().flush(sinks); }

  bool exhausted() override { return stopped_ && !live_->consumer().next_rx(); }

  void stop() override {
    if (stopped_) return;
    stopped_ = true;
    if (livox_) livox_->stop();
    if (fetcher_) fetcher_->stop();
    live_->stop();
  }

  std::optional<drivers::capture::SourceHealth> health(HostTime now) override {
    drivers::capture::SourceHealth h = live_->update_health(now);
    if (livox_) livox_->annotate(h);
    if (reinit_) reinit_->note_health(h);
    return h;
  }

  void supervise(HostTime now) override {
    if (reinit_) reinit_->maintain(live_->consumer(), now);
  }

  [[nodiscard]] std::string summary() const override {
    const auto c = live_->consumer().decoder_counters();
    std::uint64_t kernel = 0;
    std::uint64_t overruns = 0;
    for (std::size_t i = 0; i < live_->stream_count(); ++i) {
      const auto k = live_->stream(i).counters();
      kernel += k.kernel_drops;
      overruns += k.ring_overruns;
    }
    return "udp: kernel drops " + std::to_string(kernel) + ", ring overruns " +
           std::to_string(overruns) + "; packets " + std::to_string(c.packets) + ", scans " +
           std::to_string(c.scans) + " (" + std::to_string(c.incomplete_scans) +
           " incomplete), points " + std::to_string(c.points) + ", sequence gaps " +
           std::to_string(c.sequence_gaps) + ", decode errors " + std::to_string(c.decode_errors);
  }

  [[nodiscard]] std::vector<SourceThread> threads() const override {
    std::vector<SourceThread> out;
    for (std::size_t i = 0; i < live_->stream_count(); ++i) {
      const drivers::capture::UdpStream* stream = &live_->stream(i);
      out.push_back(
          {name_ + "." + stream_names_[i], [stream] { return stream->counters().wakeups; }});
    }
    return out;
  }

  [[nodiscard]] std::vector<std::pair<std::string, std::uint16_t>> local_ports() const override {
    std::vector<std::pair<std::string, std::uint16_t>> out;
    for (std::size_t i = 0; i < live_->stream_count(); ++i) {
      out.emplace_back(stream_names_[i], live_->stream(i).local_port());
    }
    if (livox_) out.emplace_back("command", livox_->command_port());
    return out;
  }

 private:
  std::string name_;
  std::vector<std::string> stream_names_;
  // Destroyed in reverse: the supervisors stop before the streams they watch.
  std::unique_ptr<drivers::capture::LiveSource> live_;
  std::unique_ptr<livox::LivoxSupervisor> livox_;
  std::unique_ptr<drivers::ouster::OusterMetadataFetcher> fetcher_;
  std::unique_ptr<drivers::ouster::OusterReinitHandler> reinit_;
  bool stopped_ = false;
};

}  // namespace

std::unique_ptr<LiveLidarSource> open_live_lidar(const SensorConfig& sensor,
                                                 const LiveOptions& options) {
  return std::make_unique<LiveLidar>(sensor, options);
}

}  // namespace livod::daemon::runtime
