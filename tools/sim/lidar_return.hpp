#pragma once
// What one LiDAR firing reports: the ray (or, with a beam footprint, three rays) cast into the
// scene at the firing time, foliage entered and left, echoes merged or competing, then the range
// model (RangeModel in sensor_sim.hpp): signal-limited detection, noise growing with range and
// incidence, range walk of weak echoes, dropouts. Every simulated LiDAR calls this for each firing
// and only quantises and encodes what it returns, so a new model (Hesai, ...) gets every effect by
// calling measure_return() with its beam direction.

#include <Eigen/Core>
#include <random>

#include "tools/sim/sensor_sim.hpp"

namespace livod::sim {

struct LidarReturn {
  bool valid = false;         // false: no return (nothing hit, too weak, dropped, out of range)
  double range_m = 0.0;       // measured range along the firing direction (noise and bias in)
  double reflectivity = 0.0;  // 0..1, of the echo the sensor reports (energy-weighted)
  double incidence_cos = 0.0;
  double true_range_m = 0.0;  // the echo's range before noise and bias (tests, diagnostics)
};

// `origin` and unit `dir` in the world; `up` is the sensor's vertical axis in the world (the
// footprint's across-scan axis is dir x up, its other axis the beam column). `rng` is the
// sensor's own stream, so the result is deterministic for a seed and a firing order.
LidarReturn measure_return(const SceneContext& scene, double time, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& dir, const Eigen::Vector3d& up,
                           const RangeModel& model, std::mt19937_64& rng);

}  // namespace livod::sim
