#include "tools/sim/livox_sim.hpp"

#include <cmath>
#include <random>

#include "drivers/livox/packets.hpp"
#include "tools/sim/lidar_return.hpp"

namespace livod::sim {
namespace {

constexpr std::size_t kPointsPerPacket = 96;

struct PatternParams {
  bool sdk2 = false;
  std::uint32_t interval_ns = 4167;
  int lines = 6;
  std::uint16_t src_port = 65000;
  std::uint16_t data_port = 56001;
  std::uint16_t imu_port = 56001;
  // Internal IMU relative to the point frame (x_sensor = T_sensor_imu * x_imu).
  Eigen::Vector3d t_sensor_imu = Eigen::Vector3d::Zero();
};

class SimLivox final : public SimLidar {
 public:
  SimLivox(std::string model, PatternParams pattern, const SimLidarOptions& options)
      : model_(std::move(model)),
        pattern_(pattern),
        options_(options),
        clock_(options.clock, options.seed ^ 0x1111),
        link_(options.link, options.seed ^ 0x2222),
        imu_(options.imu_noise, options.seed ^ 0x3333),
        rng_(options.seed) {
    T_sensor_imu_.translation() = pattern.t_sensor_imu;
  }

  [[nodiscard]] std::string model() const override { return model_; }

  void run(double t_begin, double t_end, const SceneContext& scene, SimOutputs& out) override {
    const double interval_s = pattern_.interval_ns * 1e-9;
    const double packet_s = interval_s * kPointsPerPacket;
    // Packets start at multiples of the packet period since t = 0 (the first point).
    auto k = static_cast<std::int64_t>(std::ceil(t_begin / packet_s - 1e-9));
    for (;; ++k) {
      const double t0 = static_cast<double>(k) * packet_s;
      if (t0 >= t_end) break;
      emit_packet(t0, interval_s, scene, out);
    }
    if (options_.imu) {
      const double imu_period = 1.0 / options_.imu_noise.rate_hz;
      auto j = static_cast<std::int64_t>(std::ceil(t_begin / imu_period - 1e-9));
      for (;; ++j) {
        const double t = static_cast<double>(j) * imu_period;
        if (t >= t_end) break;
        emit_imu(t, scene, out);
      }
    }
  }

  std::vector<std::filesystem::path> write_side_files(const std::filesystem::path&,
                                                      const std::string&) const override {
    return {};
  }

 private:
  // Beam direction (unit, sensor frame) of laser `line` at time t.
  [[nodiscard]] Eigen::Vector3d direction(double t, int line) const {
    double az = 0.0;
    double el = 0.0;
    if (!pattern_.sdk2) {
      // Risley-prism rosette: two counter-rotating deflections of 19.3 deg each reach 38.6 deg
      // off axis; the six lasers sit on a short vertical line 0.9 deg apart.
      const double a = 19.3 * M_PI / 180.0;
      const double w1 = 2.0 * M_PI * 97.3;
      const double w2 = -2.0 * M_PI * 61.9;
      az = a * (std::cos(w1 * t) + std::cos(w2 * t));
      el = a * (std::sin(w1 * t) + std::sin(w2 * t)) * (77.2 / 70.4) +
           (line - 2.5) * 0.9 * M_PI / 180.0;
    } else {
      // Mid-360: full turns at 10 Hz with a fast incommensurate elevation sweep per laser,
      // covering -7..52 deg.
      az = 2.0 * M_PI * 10.0 * t + line * (M_PI / 2.0);
      const double centre = 22.5 * M_PI / 180.0;
      const double half = 29.5 * M_PI / 180.0;
      el = centre + half * std::sin(2.0 * M_PI * 1371.7 * t + line * 1.3);
    }
    return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  }

  void emit_packet(double t0, double interval_s, const SceneContext& scene, SimOutputs& out) {
    std::array<livox::LivoxPoint, kPointsPerPacket> pts{};
    for (std::size_t i = 0; i < kPointsPerPacket; ++i) {
      const double t = t0 + static_cast<double>(i) * interval_s;
      const int line = static_cast<int>(i % static_cast<std::size_t>(pattern_.lines));
      const Eigen::Vector3d dir = direction(t, line);
      const Eigen::Isometry3d T_world_sensor = scene.T_world_sensor(t);
      SimPointTruth truth;
      truth.t = t;
      truth.ring = static_cast<std::uint16_t>(line);
      auto& p = pts[i];
      const LidarReturn ret =
          measure_return(scene, t, T_world_sensor.translation(), T_world_sensor.linear() * dir,
                         T_world_sensor.linear().col(2), options_.range, rng_);
      if (ret.valid) {
        const Eigen::Vector3d q = dir * ret.range_m;
        // Quantise exactly as the wire does so that the truth equals the decoded point.
        p.x = static_cast<float>(std::lround(q.x() * 1000.0) / 1000.0);
        p.y = static_cast<float>(std::lround(q.y() * 1000.0) / 1000.0);
        p.z = static_cast<float>(std::lround(q.z() * 1000.0) / 1000.0);
        p.valid = !(p.x == 0.0F && p.y == 0.0F && p.z == 0.0F);
        p.reflectivity = static_cast<std::uint8_t>(
            std::clamp(ret.reflectivity * options_.range.reflectivity_gain, 0.0, 255.0));
        truth.p_sensor = Eigen::Vector3d(p.x, p.y, p.z);
        truth.reflectivity = p.reflectivity;
        truth.valid = p.valid;
      }
      if (out.on_point) out.on_point(truth);
    }
    const std::int64_t stamp = clock_.stamp_ns(t0);
    std::vector<std::byte> payload;
    if (!pattern_.sdk2) {
      livox::Sdk1Header h;
      h.data_type = 2;
      h.timestamp_type = 0;
      h.timestamp = static_cast<std::uint64_t>(stamp);
      payload = livox::encode_sdk1_points(h, pts);
    } else {
      livox::Sdk2Header h;
      h.data_type = 1;
      h.timestamp_ns = static_cast<std::uint64_t>(stamp);
      h.time_interval_100ns =
          static_cast<std::uint16_t>((kPointsPerPacket - 1) * pattern_.interval_ns / 100);
      h.udp_cnt = udp_cnt_++;
      payload = livox::encode_sdk2_points(h, pts);
    }
    send(t0 + static_cast<double>(kPointsPerPacket - 1) * interval_s, pattern_.data_port,
         std::move(payload), out);
  }

  void emit_imu(double t, const SceneContext& scene, SimOutputs& out) {
    const Eigen::Isometry3d T_body_imu = scene.T_body_sensor * T_sensor_imu_;
    const ImuTruth ideal = scene.imu_truth(t, T_body_imu);
    const ImuTruth m = imu_.measure(ideal);
    if (out.on_imu) out.on_imu(SimImuTruth{t, m.gyro_rad_s, m.accel_m_s2});
    const std::int64_t stamp = clock_.stamp_ns(t);
    std::vector<std::byte> payload;
    if (!pattern_.sdk2) {
      livox::Sdk1Header h;
      h.timestamp = static_cast<std::uint64_t>(stamp);
      payload = livox::encode_sdk1_imu(h, m.gyro_rad_s, m.accel_m_s2);
    } else {
      livox::Sdk2Header h;
      h.timestamp_ns = static_cast<std::uint64_t>(stamp);
      h.write_crc = true;
      payload = livox::encode_sdk2_imu(h, m.gyro_rad_s, m.accel_m_s2);
    }
    send(t, pattern_.imu_port, std::move(payload), out);
  }

  void send(double t_sent, std::uint16_t port, std::vector<std::byte>&& payload, SimOutputs& out) {
    const double delay = link_.delay_s();
    if (delay < 0.0) return;  // lost
    SimDatagram d;
    d.host_time_ns =
        static_cast<std::int64_t>(std::llround((options_.host_epoch_s + t_sent + delay) * 1e9));
    d.src_ip = options_.sensor_ip;
    d.src_port = pattern_.src_port;
    d.dst_port = port;
    d.payload = std::move(payload);
    out.on_datagram(std::move(d));
  }

  std::string model_;
  PatternParams pattern_;
  SimLidarOptions options_;
  SensorClock clock_;
  Link link_;
  ImuModel imu_;
  std::mt19937_64 rng_;
  Eigen::Isometry3d T_sensor_imu_ = Eigen::Isometry3d::Identity();
  std::uint16_t udp_cnt_ = 0;
};

}  // namespace

std::unique_ptr<SimLidar> make_sim_avia(const SimLidarOptions& options) {
  PatternParams p;
  p.sdk2 = false;
  p.interval_ns = 4167;
  p.lines = 6;
  p.src_port = 65000;
  p.data_port = 56001;
  p.imu_port = 56001;
  // FAST-LIVO2's Avia extrinsic puts the LiDAR at (0.04165, 0.02326, -0.0284) in the IMU frame.
  p.t_sensor_imu = Eigen::Vector3d(-0.04165, -0.02326, 0.0284);
  return std::make_unique<SimLivox>("AVIA", p, options);
}

std::unique_ptr<SimLidar> make_sim_mid360(const SimLidarOptions& options) {
  PatternParams p;
  p.sdk2 = true;
  p.interval_ns = 5000;
  p.lines = 4;
  p.src_port = 56300;
  p.data_port = 56301;
  p.imu_port = 56401;
  // FAST_LIO's Mid-360 extrinsic: LiDAR at (-0.011, -0.02329, 0.04412) in the IMU frame.
  p.t_sensor_imu = Eigen::Vector3d(0.011, 0.02329, -0.04412);
  return std::make_unique<SimLivox>("MID-360", p, options);
}

}  // namespace livod::sim
