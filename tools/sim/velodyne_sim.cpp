#include "tools/sim/velodyne_sim.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/data_packet.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::sim {
namespace {

namespace vel = drivers::velodyne;

constexpr double kSequenceUs = 55.296;  // one 16-laser firing sequence (sensor-protocols 4.3)
constexpr double kPacketS = 24 * kSequenceUs * 1e-6;  // 12 blocks x 2 sequences
constexpr double kRotationHz = 10.0;                  // 600 RPM
constexpr double kDistanceUnitM = 0.002;
constexpr std::uint16_t kDataPort = 2368;
constexpr std::uint16_t kPositionPort = 8308;
constexpr std::uint16_t kPlaceholderRaw = 500;  // 1 m

void put_u16(std::vector<std::byte>& b, std::size_t at, std::uint16_t v) {
  b[at] = static_cast<std::byte>(v & 0xFF);
  b[at + 1] = static_cast<std::byte>(v >> 8);
}

void put_u32(std::vector<std::byte>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i)
    b[at + static_cast<std::size_t>(i)] = static_cast<std::byte>((v >> (8 * i)) & 0xFF);
}

class SimVlp16 final : public SimLidar {
 public:
  explicit SimVlp16(const SimLidarOptions& options)
      : options_(options),
        clock_(options.clock, options.seed ^ 0x4444),
        link_(options.link, options.seed ^ 0x5555),
        rng_(options.seed),
        decoder_(vel::Model::kVlp16, vel::default_calibration(vel::Model::kVlp16),
                 vel::DecodeSettings{}) {}

  [[nodiscard]] std::string model() const override { return "VLP-16"; }

  void run(double t_begin, double t_end, const SceneContext& scene, SimOutputs& out) override {
    auto k = static_cast<std::int64_t>(std::ceil(t_begin / kPacketS - 1e-9));
    for (;; ++k) {
      const double t0 = static_cast<double>(k) * kPacketS;
      if (t0 >= t_end) break;
      emit_data(t0, scene, out);
    }
    const double pos_period = 0.1;
    auto j = static_cast<std::int64_t>(std::ceil(t_begin / pos_period - 1e-9));
    for (;; ++j) {
      const double t = static_cast<double>(j) * pos_period;
      if (t >= t_end) break;
      emit_position(t, out);
    }
  }

  std::vector<std::filesystem::path> write_side_files(const std::filesystem::path&,
                                                      const std::string&) const override {
    return {};  // the decoder's built-in VLP-16 table is what the simulator uses
  }

 private:
  [[nodiscard]] std::uint32_t toh_us(double t) {
    const std::int64_t ns = clock_.stamp_ns(t);
    const std::int64_t us = ns / 1000;
    const std::int64_t hour_us = 3'600'000'000LL;
    return static_cast<std::uint32_t>(((us % hour_us) + hour_us) % hour_us);
  }

  void emit_data(double t0, const SceneContext& scene, SimOutputs& out) {
    std::vector<std::byte> payload(vel::wire::kDataPacketSize, std::byte{0});
    for (int b = 0; b < vel::wire::kBlocksPerPacket; ++b) {
      const std::size_t base = static_cast<std::size_t>(b) * vel::wire::kBlockSize;
      const double t_block = t0 + 2.0 * b * kSequenceUs * 1e-6;
      const double turns = t_block * kRotationHz;
      const auto azimuth = static_cast<std::uint16_t>(
          static_cast<std::int64_t>(std::llround((turns - std::floor(turns)) * 36000.0)) % 36000);
      put_u16(payload, base, vel::wire::kBank0Flag);
      put_u16(payload, base + 2, azimuth);
      for (int c = 0; c < vel::wire::kChannelsPerBlock; ++c) {
        put_u16(payload, base + 4 + static_cast<std::size_t>(c) * 3, kPlaceholderRaw);
      }
    }
    put_u32(payload, vel::wire::kTimestampOffset, toh_us(t0));
    payload[vel::wire::kReturnModeOffset] = std::byte{0x37};
    payload[vel::wire::kFactoryByteOffset] = std::byte{0x22};

    // The decoder's view of this packet at 1 m: per-return direction and firing time.
    const auto geometry =
        decoder_.decode(payload, std::numeric_limits<double>::quiet_NaN(), returns_);
    std::normal_distribution<double> noise(0.0, options_.range.sigma_m);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (std::size_t i = 0; i < geometry.count; ++i) {
      const vel::DecodedReturn& r = returns_[i];
      const std::size_t b = i / vel::wire::kChannelsPerBlock;
      const std::size_t c = i % vel::wire::kChannelsPerBlock;
      const std::size_t at = b * vel::wire::kBlockSize + 4 + c * 3;
      const Eigen::Vector3d dir = Eigen::Vector3d(r.x, r.y, r.z).normalized();
      const double t = t0 + r.t_offset_ns * 1e-9;
      const Eigen::Isometry3d T_world_sensor = scene.T_world_sensor(t);
      Hit hit;
      std::uint16_t raw = 0;
      std::uint8_t refl = 0;
      SimPointTruth truth;
      truth.t = t;
      truth.ring = r.ring;
      if (scene.world->intersect(T_world_sensor.translation(), T_world_sensor.linear() * dir, 1e-3,
                                 options_.range.max_range_m, hit) &&
          hit.range >= options_.range.min_range_m &&
          unit(rng_) >= options_.range.dropout_probability) {
        const double measured = hit.range + noise(rng_);
        const long counts = std::lround(measured / kDistanceUnitM);
        if (counts > 0 && counts < 65536) {
          raw = static_cast<std::uint16_t>(counts);
          refl = static_cast<std::uint8_t>(
              std::clamp(hit.surface->reflectivity * options_.range.reflectivity_gain, 0.0, 255.0));
          truth.valid = true;
          truth.p_sensor = dir * (raw * kDistanceUnitM);
          truth.reflectivity = refl;
        }
      }
      put_u16(payload, at, raw);
      payload[at + 2] = static_cast<std::byte>(refl);
      if (out.on_point) out.on_point(truth);
    }
    send(t0 + kPacketS, kDataPort, std::move(payload), out);
  }

  void emit_position(double t, SimOutputs& out) {
    std::vector<std::byte> payload(vel::wire::kPositionPacketSize, std::byte{0});
    const std::uint32_t toh = toh_us(t);
    put_u32(payload, vel::wire::kPositionTimestampOffset, toh);
    payload[vel::wire::kPpsStatusOffset] = std::byte{0};  // free-running: no PPS
    // A receiver without a fix sends status V; time fields follow the sensor clock.
    const std::uint32_t s = toh / 1'000'000;
    char nmea[96];
    std::snprintf(nmea, sizeof(nmea), "$GPRMC,00%02u%02u,V,,,,,,,,,,N", s / 60 % 60, s % 60);
    unsigned checksum = 0;
    for (const char* p = nmea + 1; *p != '\0'; ++p) checksum ^= static_cast<unsigned char>(*p);
    char full[112];
    const int n = std::snprintf(full, sizeof(full), "%s*%02X\r\n", nmea, checksum);
    std::memcpy(payload.data() + vel::wire::kNmeaOffset, full, static_cast<std::size_t>(n));
    send(t, kPositionPort, std::move(payload), out);
  }

  void send(double t_sent, std::uint16_t port, std::vector<std::byte>&& payload, SimOutputs& out) {
    const double delay = link_.delay_s();
    if (delay < 0.0) return;
    SimDatagram d;
    d.host_time_ns =
        static_cast<std::int64_t>(std::llround((options_.host_epoch_s + t_sent + delay) * 1e9));
    d.src_ip = options_.sensor_ip;
    d.src_port = 2368;
    d.dst_port = port;
    d.payload = std::move(payload);
    out.on_datagram(std::move(d));
  }

  SimLidarOptions options_;
  SensorClock clock_;
  Link link_;
  std::mt19937_64 rng_;
  vel::DataPacketDecoder decoder_;
  std::array<vel::DecodedReturn, vel::DataPacketDecoder::kMaxReturns> returns_{};
};

}  // namespace

std::unique_ptr<SimLidar> make_sim_vlp16(const SimLidarOptions& options) {
  return std::make_unique<SimVlp16>(options);
}

}  // namespace livod::sim
