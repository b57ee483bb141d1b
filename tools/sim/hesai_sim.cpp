#include "tools/sim/hesai_sim.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>

#include "core/error.hpp"
#include "drivers/hesai/calibration.hpp"
#include "drivers/hesai/firing_timing.hpp"
#include "drivers/hesai/geometry.hpp"
#include "drivers/hesai/hesai_decoder.hpp"
#include "drivers/hesai/packet.hpp"
#include "tools/sim/lidar_return.hpp"

namespace livod::sim {
namespace {

namespace hs = drivers::hesai;

constexpr int kBlocks = 8;
constexpr int kChannels = 32;

// The simulated unit's angle correction file: the XT32's nominal 1-degree spacing from +15 to
// -16 degrees with unit-specific offsets of the size real files show (elevation within 0.05
// degree, azimuth within 0.13 degree).
hs::AngleCorrections unit_corrections() {
  hs::AngleCorrections k;
  k.source = "simulated PANDARXT32";
  for (int c = 0; c < kChannels; ++c) {
    const double elevation = 15.0 - c - 0.03 * std::sin(0.7 * c);
    const double azimuth = 0.08 - 0.0065 * c + 0.01 * std::cos(1.3 * c);
    k.channels.push_back({std::round(elevation * 1e6) / 1e6, std::round(azimuth * 1e6) / 1e6});
  }
  return k;
}

class SimPandarXt32 final : public SimLidar {
 public:
  explicit SimPandarXt32(const SimLidarOptions& options)
      : options_(options),
        clock_(options.clock, options.seed ^ 0x4444),
        link_(options.link, options.seed ^ 0x5555),
        rng_(options.seed),
        // 600 RPM (the factory setting) or 1200 RPM for scan_rate_hz 20: the firing round stays
        // 50 us, so the azimuth step doubles.
        rotation_hz_(options.scan_rate_hz >= 15.0 ? 20.0 : 10.0),
        corrections_(unit_corrections()),
        geometry_(corrections_),
        timing_(hs::Model::kPandarXT32),
        round_s_(hs::traits(hs::Model::kPandarXT32).firing_round_ns * 1e-9),
        packet_s_(static_cast<double>(timing_.packet_period_ns(false)) * 1e-9) {}

  [[nodiscard]] std::string model() const override { return "PANDARXT32"; }

  void run(double t_begin, double t_end, const SceneContext& scene, SimOutputs& out) override {
    auto k = static_cast<std::int64_t>(std::ceil(t_begin / packet_s_ - 1e-9));
    for (;; ++k) {
      const double t_first_round = static_cast<double>(k) * packet_s_;
      if (t_first_round >= t_end) break;
      emit(k, t_first_round, scene, out);
    }
  }

  std::vector<std::filesystem::path> write_side_files(const std::filesystem::path& dir,
                                                      const std::string& stem) const override {
    const std::filesystem::path path = dir / (stem + ".csv");
    std::ofstream os(path, std::ios::binary);
    os << hs::format_angle_corrections(corrections_);
    os.flush();
    if (!os) throw Error("cannot write the angle correction file " + path.string());
    return {path};
  }

 private:
  void emit(std::int64_t k, double t_first_round, const SceneContext& scene, SimOutputs& out) {
    hs::HesaiPacket p;
    p.model = hs::Model::kPandarXT32;
    p.returns = 1;
    p.return_mode = 0x37;
    p.first_block_return = 0;
    p.distance_unit_m = 0.004;
    p.motor_rpm = static_cast<std::uint16_t>(std::lround(rotation_hz_ * 60.0));
    p.udp_sequence = static_cast<std::uint32_t>(k + 1);
    // The packet time dates the last round (block 7): its round starts block_start_ns after it.
    const double t_last_round = t_first_round + (kBlocks - 1) * round_s_;
    const double t_packet = t_last_round - timing_.block_start_ns(false, kBlocks - 1) * 1e-9;
    const std::int64_t stamp = clock_.stamp_ns(t_packet);
    p.timestamp_ns = stamp - ((stamp % 1000) + 1000) % 1000;  // the tail keeps microseconds
    for (int b = 0; b < kBlocks; ++b) {
      // The block azimuth is the head's angle at the round's first firing.
      const double t_round = t_first_round + b * round_s_;
      const double turns = t_round * rotation_hz_;
      const auto azimuth = static_cast<std::uint16_t>(
          static_cast<std::int64_t>(std::llround((turns - std::floor(turns)) * 36000.0)) % 36000);
      p.azimuth[static_cast<std::size_t>(b)] = azimuth;
      const hs::BlockAngle angle = hs::block_angle(azimuth);
      for (int c = 0; c < kChannels; ++c) {
        Eigen::Vector3d dir;
        geometry_.point(angle, c, 1.0, dir.x(), dir.y(), dir.z());
        const double t =
            t_packet + (timing_.offset_ns(false, b, c)) * 1e-9;  // the channel's firing
        const Eigen::Isometry3d T_world_sensor = scene.T_world_sensor(t);
        std::uint16_t raw = 0;
        std::uint8_t refl = 0;
        SimPointTruth truth;
        truth.t = t;
        truth.ring = static_cast<std::uint16_t>(kChannels - 1 - c);  // channel 1 is the top beam
        // Everything a real return goes through (lidar_return.hpp): footprint, moving objects,
        // foliage, signal-limited detection, range noise and walk, dropouts.
        const LidarReturn ret =
            measure_return(scene, t, T_world_sensor.translation(), T_world_sensor.linear() * dir,
                           T_world_sensor.linear().col(2), options_.range, rng_);
        if (ret.valid) {
          const long counts = std::lround(ret.range_m / p.distance_unit_m);
          if (counts > 0 && counts < 65536) {
            raw = static_cast<std::uint16_t>(counts);
            refl = static_cast<std::uint8_t>(
                std::clamp(ret.reflectivity * options_.range.reflectivity_gain, 0.0, 255.0));
            truth.valid = true;
            truth.p_sensor = dir * (raw * p.distance_unit_m);
            truth.reflectivity = refl;
          }
        }
        const auto i = static_cast<std::size_t>(b * hs::kMaxChannels + c);
        p.distance[i] = raw;
        p.reflectivity[i] = refl;
        if (out.on_point) out.on_point(truth);
      }
    }
    send(t_last_round + round_s_, hs::encode_packet(p), out);
  }

  void send(double t_sent, std::vector<std::byte>&& payload, SimOutputs& out) {
    const double delay = link_.delay_s();
    if (delay < 0.0) return;
    SimDatagram d;
    d.host_time_ns =
        static_cast<std::int64_t>(std::llround((options_.host_epoch_s + t_sent + delay) * 1e9));
    d.src_ip = options_.sensor_ip;
    d.src_port = hs::kDataPort;
    d.dst_port = hs::kDataPort;
    d.payload = std::move(payload);
    out.on_datagram(std::move(d));
  }

  SimLidarOptions options_;
  SensorClock clock_;
  Link link_;
  std::mt19937_64 rng_;
  double rotation_hz_;
  hs::AngleCorrections corrections_;
  hs::BeamGeometry geometry_;
  hs::FiringTiming timing_;
  double round_s_;
  double packet_s_;
};

}  // namespace

std::unique_ptr<SimLidar> make_sim_pandar_xt32(const SimLidarOptions& options) {
  return std::make_unique<SimPandarXt32>(options);
}

}  // namespace livod::sim
