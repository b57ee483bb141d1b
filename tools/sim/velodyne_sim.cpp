#include "tools/sim/velodyne_sim.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/data_packet.hpp"
#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/wire.hpp"
#include "tools/sim/lidar_return.hpp"
#include "tools/sim/velodyne_position_encoder.hpp"

namespace livod::sim {
namespace {

namespace vel = drivers::velodyne;

constexpr std::uint16_t kDataPort = 2368;
constexpr std::uint16_t kPositionPort = 8308;
constexpr std::uint16_t kPlaceholderRaw = 500;  // 1 m at 2 mm
constexpr std::uint8_t kStrongestReturn = 0x37;
constexpr std::int64_t kMicrosecondsPerHour = 3'600'000'000LL;

// What differs between the simulated Velodyne models.
struct VelodyneSimSpec {
  vel::Model model = vel::Model::kVlp16;
  std::string name;
  double rotation_hz = 10.0;  // 600 RPM, the factory setting
  double position_period_s = 0.1;
  std::uint16_t position_src_port = kDataPort;
  // HDL-32E: the three motion sensors' temperatures (C); nullopt: no motion sensors.
  std::optional<std::array<double, 3>> motion_temperatures_c;
};

class SimVelodyne final : public SimLidar {
 public:
  SimVelodyne(VelodyneSimSpec spec, const SimLidarOptions& options)
      : spec_(std::move(spec)),
        options_(options),
        clock_(options.clock, options.seed ^ 0x4444),
        link_(options.link, options.seed ^ 0x5555),
        rng_(options.seed),
        imu_(imu_params(options.imu_noise, spec_.position_period_s), options.seed ^ 0x3333),
        decoder_(spec_.model, vel::default_calibration(spec_.model), vel::DecodeSettings{}),
        distance_unit_m_(vel::traits(spec_.model).distance_unit_m),
        packet_s_(static_cast<double>(decoder_.timing().packet_period_ns(false)) * 1e-9) {
    // 600 RPM (the factory setting) or 1200 RPM for scan_rate_hz 20.
    spec_.rotation_hz = options.scan_rate_hz >= 15.0 ? 20.0 : 10.0;
  }

  [[nodiscard]] std::string model() const override { return spec_.name; }

  void run(double t_begin, double t_end, const SceneContext& scene, SimOutputs& out) override {
    auto k = static_cast<std::int64_t>(std::ceil(t_begin / packet_s_ - 1e-9));
    for (;; ++k) {
      const double t0 = static_cast<double>(k) * packet_s_;
      if (t0 >= t_end) break;
      emit_data(t0, scene, out);
    }
    const double period = spec_.position_period_s;
    auto j = static_cast<std::int64_t>(std::ceil(t_begin / period - 1e-9));
    for (;; ++j) {
      const double t = static_cast<double>(j) * period;
      if (t >= t_end) break;
      emit_position(t, scene, out);
    }
  }

  std::vector<std::filesystem::path> write_side_files(const std::filesystem::path&,
                                                      const std::string&) const override {
    return {};  // the decoder's built-in calibration table is what the simulator uses
  }

 private:
  // The motion sensors are sampled once per position packet, whatever rate the options name.
  static ImuNoiseParams imu_params(ImuNoiseParams p, double period_s) {
    p.rate_hz = 1.0 / period_s;
    return p;
  }

  [[nodiscard]] std::uint32_t toh_us(double t) {
    const std::int64_t us = clock_.stamp_ns(t) / 1000;
    return static_cast<std::uint32_t>(((us % kMicrosecondsPerHour) + kMicrosecondsPerHour) %
                                      kMicrosecondsPerHour);
  }

  void emit_data(double t0, const SceneContext& scene, SimOutputs& out) {
    std::vector<std::byte> payload(vel::wire::kDataPacketSize, std::byte{0});
    for (int b = 0; b < vel::wire::kBlocksPerPacket; ++b) {
      const std::size_t base = static_cast<std::size_t>(b) * vel::wire::kBlockSize;
      // The block azimuth is the head's angle at the block's first firing.
      const double t_block =
          t0 + static_cast<double>(decoder_.timing().block_reference_ns(false, b)) * 1e-9;
      const double turns = t_block * spec_.rotation_hz;
      const auto azimuth = static_cast<std::uint16_t>(
          static_cast<std::int64_t>(std::llround((turns - std::floor(turns)) * 36000.0)) % 36000);
      vel::wire::put_u16le(payload, base, vel::wire::kBank0Flag);
      vel::wire::put_u16le(payload, base + 2, azimuth);
      for (int c = 0; c < vel::wire::kChannelsPerBlock; ++c) {
        vel::wire::put_u16le(payload, base + 4 + static_cast<std::size_t>(c) * 3, kPlaceholderRaw);
      }
    }
    vel::wire::put_u32le(payload, vel::wire::kTimestampOffset, toh_us(t0));
    payload[vel::wire::kReturnModeOffset] = std::byte{kStrongestReturn};
    payload[vel::wire::kFactoryByteOffset] = std::byte{vel::traits(spec_.model).factory_byte};

    // The decoder's view of this packet at 1 m: per-return direction and firing time.
    const auto geometry =
        decoder_.decode(payload, std::numeric_limits<double>::quiet_NaN(), returns_);
    for (std::size_t i = 0; i < geometry.count; ++i) {
      const vel::DecodedReturn& r = returns_[i];
      const std::size_t b = i / vel::wire::kChannelsPerBlock;
      const std::size_t c = i % vel::wire::kChannelsPerBlock;
      const std::size_t at = b * vel::wire::kBlockSize + 4 + c * 3;
      const Eigen::Vector3d dir = Eigen::Vector3d(r.x, r.y, r.z).normalized();
      const double t = t0 + r.t_offset_ns * 1e-9;
      const Eigen::Isometry3d T_world_sensor = scene.T_world_sensor(t);
      std::uint16_t raw = 0;
      std::uint8_t refl = 0;
      SimPointTruth truth;
      truth.t = t;
      truth.ring = r.ring;
      const LidarReturn ret =
          measure_return(scene, t, T_world_sensor.translation(), T_world_sensor.linear() * dir,
                         T_world_sensor.linear().col(2), options_.range, rng_);
      if (ret.valid) {
        const long counts = std::lround(ret.range_m / distance_unit_m_);
        if (counts > 0 && counts < 65536) {
          raw = static_cast<std::uint16_t>(counts);
          refl = static_cast<std::uint8_t>(
              std::clamp(ret.reflectivity * options_.range.reflectivity_gain, 0.0, 255.0));
          truth.valid = true;
          truth.p_sensor = dir * (raw * distance_unit_m_);
          truth.reflectivity = refl;
        }
      }
      vel::wire::put_u16le(payload, at, raw);
      payload[at + 2] = static_cast<std::byte>(refl);
      if (out.on_point) out.on_point(truth);
    }
    send(t0 + packet_s_, kDataPort, kDataPort, std::move(payload), out);
  }

  void emit_position(double t, const SceneContext& scene, SimOutputs& out) {
    const std::uint32_t toh = toh_us(t);
    std::optional<Hdl32eMotionWords> words;
    if (spec_.motion_temperatures_c) {
      if (options_.imu) {
        // The IMU frame is the LiDAR frame (see velodyne_sim.hpp): T_body_imu = T_body_sensor.
        const ImuTruth m = imu_.measure(scene.imu_truth(t, scene.T_body_sensor));
        if (out.on_imu) out.on_imu(SimImuTruth{t, m.gyro_rad_s, m.accel_m_s2});
        words = encode_hdl32e_motion(m.gyro_rad_s, m.accel_m_s2, *spec_.motion_temperatures_c);
      }
    }
    send(t, spec_.position_src_port, kPositionPort,
         encode_position_packet(toh, words ? &*words : nullptr), out);
  }

  void send(double t_sent, std::uint16_t src_port, std::uint16_t dst_port,
            std::vector<std::byte>&& payload, SimOutputs& out) {
    const double delay = link_.delay_s();
    if (delay < 0.0) return;
    SimDatagram d;
    d.host_time_ns =
        static_cast<std::int64_t>(std::llround((options_.host_epoch_s + t_sent + delay) * 1e9));
    d.src_ip = options_.sensor_ip;
    d.src_port = src_port;
    d.dst_port = dst_port;
    d.payload = std::move(payload);
    out.on_datagram(std::move(d));
  }

  VelodyneSimSpec spec_;
  SimLidarOptions options_;
  SensorClock clock_;
  Link link_;
  std::mt19937_64 rng_;
  ImuModel imu_;
  vel::DataPacketDecoder decoder_;
  double distance_unit_m_;
  double packet_s_;
  std::array<vel::DecodedReturn, vel::DataPacketDecoder::kMaxReturns> returns_{};
};

}  // namespace

std::unique_ptr<SimLidar> make_sim_vlp16(const SimLidarOptions& options) {
  VelodyneSimSpec spec;
  spec.model = vel::Model::kVlp16;
  spec.name = "VLP-16";
  return std::make_unique<SimVelodyne>(spec, options);
}

std::unique_ptr<SimLidar> make_sim_hdl32e(const SimLidarOptions& options) {
  VelodyneSimSpec spec;
  spec.model = vel::Model::kHdl32e;
  spec.name = "HDL-32E";
  // The monterey capture: 299 position packets over 1.4866 s of top-of-hour time, sent from
  // port 8308, motion-sensor temperatures 35.1, 37.4 and 41.1 C.
  spec.position_period_s = 4.988e-3;
  spec.position_src_port = kPositionPort;
  spec.motion_temperatures_c = std::array<double, 3>{35.1, 37.4, 41.1};
  return std::make_unique<SimVelodyne>(spec, options);
}

}  // namespace livod::sim
