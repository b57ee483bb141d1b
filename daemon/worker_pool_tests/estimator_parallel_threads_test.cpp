// The LIO pipeline on the worker pool: residual rows, point covariances, undistortion and per-voxel
// map refits run on several threads. Under ThreadSanitizer (label "threads") this checks that the
// parallel parts share nothing they should not; in every build it checks that the result is
// bit-identical to the single-threaded run (the estimator's determinism promise,
// estimator/task_runner.hpp). Synthetic data: a spinning 32-beam LiDAR in a box-shaped room with
// furniture, carried at walking pace, and the IMU readings of that motion.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "daemon/worker_pool.hpp"
#include "estimator/pipeline.hpp"

namespace livod {
namespace {

constexpr double kScanPeriodS = 0.1;
constexpr double kImuPeriodS = 0.005;
constexpr double kStaticS = 0.5;  // the IMU initialisation needs the platform at rest

// Axis-aligned boxes seen from inside (the room) or outside (furniture).
struct Box {
  Eigen::Vector3d lo, hi;
};

double ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b, bool inside) {
  double t_near = -1e9;
  double t_far = 1e9;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return -1.0;
      continue;
    }
    double t1 = (b.lo[a] - o[a]) / d[a];
    double t2 = (b.hi[a] - o[a]) / d[a];
    if (t1 > t2) std::swap(t1, t2);
    t_near = std::max(t_near, t1);
    t_far = std::min(t_far, t2);
  }
  if (t_near > t_far) return -1.0;
  return inside ? t_far : (t_near > 0.0 ? t_near : -1.0);
}

double cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  static const Box room{{-5, -4, 0}, {5, 4, 3}};
  static const std::vector<Box> furniture = {{{2, 1, 0}, {3, 2.5, 1}},
                                             {{-3.5, -3, 0}, {-2, -2, 1.8}},
                                             {{-1, 2.8, 0.5}, {1.5, 4, 1.2}},
                                             {{3.5, -3.5, 0}, {4.5, -1, 2.2}}};
  double best = ray_box(o, d, room, true);
  for (const auto& f : furniture) {
    const double t = ray_box(o, d, f, false);
    if (t > 0.0 && t < best) best = t;
  }
  return best;
}

// Body position at time t: still, then a slow smooth walk along x (C2 at the start).
Eigen::Vector3d position(double t) {
  const double s = std::max(0.0, t - kStaticS);
  return {0.4 * s * s / (1.0 + s), 0.0, 1.2};
}

Eigen::Vector3d acceleration(double t) {
  const double s = std::max(0.0, t - kStaticS);
  // d2/ds2 of 0.4 s^2 / (1 + s) = 0.8 / (1 + s)^3
  return {s > 0.0 ? 0.8 / std::pow(1.0 + s, 3) : 0.0, 0.0, 0.0};
}

struct RunOutputs {
  std::vector<estimator::PipelineOutput> outputs;
};

RunOutputs run(estimator::TaskRunner* runner) {
  estimator::PipelineOptions po;
  po.runner = runner;
  po.params.lio.blind = 0.3;
  po.params.imu.init_samples = 50;
  estimator::LioPipeline pipeline(po);
  RunOutputs r;
  const auto collect = [&](const estimator::PipelineOutput& o) { r.outputs.push_back(o); };
  std::int64_t next_imu_ns = 0;
  std::uint32_t sequence = 0;
  for (double t_scan = 0.0; t_scan < 3.0; t_scan += kScanPeriodS) {
    LidarScan scan;
    scan.start.mapped = MappedTime(std::llround(t_scan * 1e9));
    scan.sequence = sequence++;
    // 360 columns over the scan period, 32 beams from -25 to +20 deg per column.
    for (int col = 0; col < 360; ++col) {
      const double dt = kScanPeriodS * col / 360.0;
      const Eigen::Vector3d o = position(t_scan + dt);
      const double az = 2.0 * M_PI * col / 360.0;
      for (int beam = 0; beam < 32; ++beam) {
        const double el = (-25.0 + 45.0 * beam / 31.0) * M_PI / 180.0;
        const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                std::sin(el));
        const double range = cast(o, d);
        const Eigen::Vector3f p = (d * range).cast<float>();
        scan.push_back(p.x(), p.y(), p.z(), 1.0F, static_cast<std::uint16_t>(beam), 0,
                       static_cast<std::int32_t>(std::llround(dt * 1e9)), range > 0.0);
      }
    }
    // IMU up to just past the scan end, then the scan.
    const double t_end = t_scan + kScanPeriodS;
    while (static_cast<double>(next_imu_ns) * 1e-9 <= t_end + kImuPeriodS) {
      ImuSample s;
      s.stamp.mapped = MappedTime(next_imu_ns);
      s.accel_m_s2 =
          acceleration(static_cast<double>(next_imu_ns) * 1e-9) + Eigen::Vector3d(0.0, 0.0, 9.81);
      pipeline.add_imu(s);
      next_imu_ns += std::llround(kImuPeriodS * 1e9);
    }
    pipeline.add_scan(scan);
    pipeline.process(collect);
  }
  return r;
}

TEST(EstimatorOnWorkerPool, ParallelRunIsBitIdenticalToTheSerialOne) {
  const RunOutputs serial = run(nullptr);
  daemon::WorkerPool pool(3);
  const RunOutputs parallel = run(&pool);
  ASSERT_GT(serial.outputs.size(), 20U);
  ASSERT_EQ(parallel.outputs.size(), serial.outputs.size());
  int updated = 0;
  for (std::size_t i = 0; i < serial.outputs.size(); ++i) {
    const auto& a = serial.outputs[i];
    const auto& b = parallel.outputs[i];
    EXPECT_EQ(a.t.ns, b.t.ns);
    // Bit-identical, not close: exact equality of every coefficient.
    EXPECT_TRUE(a.x.p_world_imu == b.x.p_world_imu) << "frame " << i;
    EXPECT_TRUE(a.x.R_world_imu == b.x.R_world_imu) << "frame " << i;
    EXPECT_TRUE(a.P == b.P) << "frame " << i;
    EXPECT_EQ(a.report.matched, b.report.matched);
    updated += a.report.updated ? 1 : 0;
  }
  EXPECT_GT(updated, 15);
  // And the odometry is right: the walk's displacement over the run.
  const auto& last = serial.outputs.back();
  const Eigen::Vector3d truth = position(last.t.seconds()) - position(0.0);
  EXPECT_LT((last.x.p_world_imu - truth).norm(), 0.02)
      << last.x.p_world_imu.transpose() << " vs " << truth.transpose();
}

}  // namespace
}  // namespace livod
