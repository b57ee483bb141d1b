#pragma once
// The interface every simulated sensor implements. A simulated sensor follows the body along the
// trajectory (rigidly mounted with T_body_sensor), samples the world along its real firing
// schedule and timing, and emits what the real sensor puts on the wire (UDP payloads, CAN frames)
// with sensor-clock stamps, delivered at host receive times through a faulty link.

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "tools/sim/moving_objects.hpp"
#include "tools/sim/sensor_clock.hpp"
#include "tools/sim/trajectory.hpp"
#include "tools/sim/world.hpp"

namespace livod::sim {

// What a simulated LiDAR needs to sample the scene.
struct SceneContext {
  const World* world = nullptr;
  const Trajectory* trajectory = nullptr;
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  Eigen::Vector3d gravity_world{0.0, 0.0, -9.81};
  const MovingObjects* movers = nullptr;  // optional: pedestrians, cars

  [[nodiscard]] Eigen::Isometry3d T_world_sensor(double t) const {
    return trajectory->at(t).T_world_body() * T_body_sensor;
  }

  // Ideal specific force and angular rate of an IMU at T_body_imu (lever-arm effects included:
  // the angular acceleration comes from a central difference of the analytic body rate).
  [[nodiscard]] ImuTruth imu_truth(double t, const Eigen::Isometry3d& T_body_imu) const {
    const TrajectoryState s = trajectory->at(t);
    const ImuTruth body = ideal_imu(s, gravity_world);
    const Eigen::Vector3d r = T_body_imu.translation();
    const Eigen::Matrix3d R_imu_body = T_body_imu.linear().transpose();
    if (r.squaredNorm() == 0.0) {
      return {R_imu_body * body.gyro_rad_s, R_imu_body * body.accel_m_s2};
    }
    constexpr double kH = 1e-4;
    const Eigen::Vector3d w = s.omega_body;
    const Eigen::Vector3d w_dot =
        (trajectory->at(t + kH).omega_body - trajectory->at(t - kH).omega_body) / (2.0 * kH);
    const Eigen::Vector3d f = body.accel_m_s2 + w_dot.cross(r) + w.cross(w.cross(r));
    return {R_imu_body * w, R_imu_body * f};
  }

  // Nearest hit of a ray at scenario time `time`: the static world, then the moving objects.
  bool intersect(double time, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                 double t_min, double t_max, Hit& hit) const {
    const bool in_world = world->intersect(origin, dir, t_min, t_max, hit);
    if (movers == nullptr || movers->empty()) return in_world;
    Hit moving;
    if (movers->intersect(time, origin, dir, t_min, in_world ? hit.range : t_max, moving)) {
      hit = moving;
      return true;
    }
    return in_world;
  }
};

// Range measurement model shared by the LiDAR models (applied by lidar_return.hpp). The first
// block is the basic model; every effect after it is off at its default, and the named scenarios
// set datasheet values per model (docs/simulator.md, "Realism").
struct RangeModel {
  double sigma_m = 0.01;  // Gaussian range noise (1 sigma) of a strong return
  double dropout_probability = 0.002;
  double min_range_m = 0.3;
  double max_range_m = 120.0;  // farthest return (with detection_limited: an 80 % target, head-on)
  double reflectivity_gain = 255.0;  // reflectivity 0..1 -> sensor units

  // Signal-limited detection: the echo of a Lambertian target of reflectivity rho at incidence
  // alpha falls as rho cos(alpha) / r^2, so the farthest return is
  //   r_limit = max_range_m sqrt(rho cos(alpha) / 0.8)
  // (the datasheets' "range at 80 % / at 10 %" pairs scale so), and the noise grows towards it:
  //   sigma = hypot(sigma_m, sigma_at_limit_m (r / r_limit)^1.2)
  // (the Ouster OS1 datasheet's precision against SNR: 1.5 cm at SNR > 250, 3 cm at 100, 10 cm
  // at 12 fits SNR^-0.6, and SNR falls as (r / r_limit)^-2).
  bool detection_limited = false;
  double sigma_at_limit_m = 0.0;
  // Range walk: a weak echo crosses the detector threshold late and reads long by up to this
  // (scaled by (r / r_limit)^2, i.e. by the inverse signal); needs detection_limited.
  double intensity_bias_m = 0.0;
  // Beam footprint, full width at half maximum across the scan (h) and along the beam column
  // (v). When > 0 every firing is three rays along the footprint's long axis; echoes closer than
  // pulse_length_m in range merge into one (mixed pixels at depth edges, a smeared range on
  // surfaces seen at grazing incidence), farther ones compete and the strongest wins.
  double divergence_h_rad = 0.0;
  double divergence_v_rad = 0.0;
  double pulse_length_m = 0.75;  // c x pulse width / 2 (5 ns)
};

// One UDP datagram as the host receives it.
struct SimDatagram {
  std::int64_t host_time_ns = 0;  // receive time on the host clock (pcap record time)
  std::uint32_t src_ip = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::vector<std::byte> payload;
};

// The exact point a LiDAR model measured, before encoding: decoders must give it back (within
// the wire format's quantisation). Expressed in the sensor frame.
struct SimPointTruth {
  double t = 0.0;  // scenario time of the firing
  Eigen::Vector3d p_sensor = Eigen::Vector3d::Zero();
  float reflectivity = 0.0F;
  std::uint16_t ring = 0;
  bool valid = false;  // false: no return (dropout, out of range, sky)
};

struct SimImuTruth {
  double t = 0.0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

struct SimOutputs {
  std::function<void(SimDatagram&&)> on_datagram;      // required
  std::function<void(const SimPointTruth&)> on_point;  // optional (tests)
  std::function<void(const SimImuTruth&)> on_imu;      // optional (tests)
};

class SimLidar {
 public:
  virtual ~SimLidar() = default;
  [[nodiscard]] virtual std::string model() const = 0;  // as `livod decode --model` spells it
  // Simulates [t_begin, t_end) of scenario time. Called once per sequence (or in consecutive
  // chunks; the model keeps its own packet counters between calls).
  virtual void run(double t_begin, double t_end, const SceneContext& scene, SimOutputs& out) = 0;
  // Files the decoder needs beside the capture (e.g. Ouster metadata JSON). Returns their paths.
  virtual std::vector<std::filesystem::path> write_side_files(const std::filesystem::path& dir,
                                                              const std::string& stem) const = 0;
};

}  // namespace livod::sim
