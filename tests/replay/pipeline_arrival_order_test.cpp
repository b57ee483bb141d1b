// The estimator's first scan must not depend on arrival order. Replay hands the estimator its
// measurements in time order; live, the LiDAR and its IMU come through different sockets and
// threads, so a scan can arrive before IMU samples older than its end. While the IMU
// initialisation is pending, a scan that arrives early must be kept until the initialisation
// decides whether it comes after it, or the live daemon starts from a different scan than replay
// (a different world frame: seen as 70 mm / 6 degrees between `livod run` and `livod replay`).

#include <gtest/gtest.h>

#include <algorithm>
#include <variant>
#include <vector>

#include "drivers/livox/livox_decoder.hpp"
#include "estimator/pipeline.hpp"
#include "estimator/sync/measurement_sync.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace livod {
namespace {

using Measurement = std::variant<LidarScan, ImuSample>;

MappedTime time_of(const Measurement& m) {
  if (const auto* s = std::get_if<LidarScan>(&m)) return estimator::MeasurementSync::scan_end(*s);
  return std::get<ImuSample>(m).stamp.mapped;
}

// A simulated Avia's scans and IMU samples in time order (a scan at its end), ideal clocks.
std::vector<Measurement> simulate_avia(double duration_s) {
  const sim::Scenario scenario = sim::make_scenario("room_handheld_avia");
  const sim::World world = sim::make_room_world(1);
  const sim::Trajectory trajectory(scenario.trajectory);
  const sim::LidarMount& mount = scenario.lidars.at(0);
  sim::SimLidarOptions options;
  options.range = mount.range;
  options.imu_noise = mount.imu_noise;
  options.seed = 3;
  auto lidar = sim::make_sim_lidar("AVIA", options);
  const sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};
  livox::LivoxDecoder decoder(*livox::livox_model("AVIA"), livox::LivoxDecoderOptions{});

  std::vector<Measurement> out;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&out](const LidarScan& s) {
    LidarScan copy = s;
    copy.start.mapped = MappedTime(s.start.sensor.ns);
    out.emplace_back(std::move(copy));
  };
  sinks.on_imu = [&out](const ImuSample& m) {
    ImuSample copy = m;
    copy.stamp.mapped = MappedTime(m.stamp.sensor.ns);
    out.emplace_back(copy);
  };
  sim::SimOutputs sim_out;
  sim_out.on_datagram = [&](sim::SimDatagram&& d) {
    decoder.on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
  };
  lidar->run(0.0, duration_s, scene, sim_out);
  std::stable_sort(out.begin(), out.end(), [](const Measurement& a, const Measurement& b) {
    return time_of(a) < time_of(b);
  });
  return out;
}

// Each scan handed over `early_ns` before its end, i.e. before the IMU samples of its last
// `early_ns` (the scan's own points are all older than those samples' arrival).
std::vector<Measurement> scans_early(std::vector<Measurement> ms, std::int64_t early_ns) {
  std::stable_sort(ms.begin(), ms.end(), [early_ns](const Measurement& a, const Measurement& b) {
    const auto key = [early_ns](const Measurement& m) {
      const std::int64_t t = time_of(m).ns;
      return std::holds_alternative<LidarScan>(m) ? t - early_ns : t;
    };
    return key(a) < key(b);
  });
  return ms;
}

struct PipelineRun {
  std::vector<estimator::PipelineOutput> outputs;
  estimator::PipelineCounters counters;
};

PipelineRun run(const std::vector<Measurement>& ms) {
  estimator::PipelineOptions po;
  po.T_imu_lidar = sim::make_scenario("room_handheld_avia").lidars.at(0).T_body_sensor;
  po.params.lio.blind = 0.3;
  estimator::LioPipeline pipeline(po);
  PipelineRun r;
  for (const Measurement& m : ms) {
    if (const auto* s = std::get_if<LidarScan>(&m)) {
      pipeline.add_scan(*s);
    } else {
      pipeline.add_imu(std::get<ImuSample>(m));
    }
    pipeline.process([&r](const estimator::PipelineOutput& o) { r.outputs.push_back(o); });
  }
  r.counters = pipeline.counters();
  return r;
}

TEST(PipelineArrivalOrder, ScansArrivingBeforeTheirImuStartTheFilterWhereTimeOrderDoes) {
  const std::vector<Measurement> in_time_order = simulate_avia(2.0);
  const PipelineRun reference = run(in_time_order);
  ASSERT_GE(reference.outputs.size(), 15U);
  // Scans that begin before the initialisation ends are dropped, the one it ends in included.
  EXPECT_GE(reference.counters.scans_before_init, 1U);

  for (const std::int64_t early_ms : {5, 20, 60}) {
    SCOPED_TRACE(early_ms);
    const PipelineRun live = run(scans_early(in_time_order, early_ms * 1'000'000));
    ASSERT_EQ(live.outputs.size(), reference.outputs.size());
    EXPECT_EQ(live.counters.scans_before_init, reference.counters.scans_before_init);
    for (std::size_t i = 0; i < live.outputs.size(); ++i) {
      const auto& a = reference.outputs[i];
      const auto& b = live.outputs[i];
      ASSERT_EQ(a.t, b.t) << "frame " << i;
      EXPECT_EQ(a.x.p_world_imu, b.x.p_world_imu) << "frame " << i;
      EXPECT_EQ(a.x.R_world_imu, b.x.R_world_imu) << "frame " << i;
    }
  }
}

}  // namespace
}  // namespace livod
