// The visual update per image at 640x512, and what it costs the LIO: a simulated handheld room
// walk (Ouster OS1-64 + its IMU + the 640x512 rig camera, `room_handheld_os1_64`) is generated
// once in memory (datagrams and rendered frames), then replayed in-process through livod's Ouster
// decoder into the pipeline, as `livod replay` runs it (worker pool of 2 for the LIO). Reported
// per image: the visual update's wall and CPU time (p50 / p99) and its split (pyramid, selection,
// update, map); per frame: the LIO part of the frame (everything but the visual update) with the
// camera and, in the LIO-only benchmark, without it (LIO per-frame time must not regress).
//
//   build/release/bench/vio_bench --benchmark_counters_tabular=true
//
// Counters are milliseconds. The machine is shared: wall times include preemption by other
// processes, CPU times do not (vio_cpu: the estimator thread's own; vio_all_cpu: the process's,
// i.e. with the worker's share of the parallel parts). The label is a hash of every pose's bits:
// a change meant to be only faster must leave it as it was.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "daemon/worker_pool.hpp"
#include "drivers/ouster/ouster_factory.hpp"
#include "estimator/pipeline.hpp"
#include "tools/sim/camera_sim.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace {

using namespace livod;

constexpr double kDurationS = 12.0;

struct Recording {
  sim::Scenario scenario = sim::make_scenario("room_handheld_os1_64");
  std::filesystem::path metadata;
  // Per 0.1 s step: the datagrams, then the frames with mid-exposure in that step.
  std::vector<std::vector<sim::SimDatagram>> datagrams;
  std::vector<std::vector<ImageFrame>> frames;
};

const Recording& recording() {
  static const Recording rec = [] {
    Recording r;
    const sim::World world = sim::make_room_world(1);
    const sim::Trajectory trajectory(r.scenario.trajectory);
    const sim::LidarMount& mount = r.scenario.lidars.at(0);
    sim::SimLidarOptions options;
    options.range = mount.range;
    options.imu_noise = mount.imu_noise;
    options.seed = 10;
    auto lidar = sim::make_sim_lidar(mount.model, options);
    const auto dir = std::filesystem::temp_directory_path() / "livod-vio-bench";
    std::filesystem::create_directories(dir);
    r.metadata = lidar->write_side_files(dir, "os1").at(0);
    const sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};
    const sim::CameraMount& cam = r.scenario.cameras.at(0);
    const sim::CameraSim camera(cam.params);
    std::mt19937_64 rng(3);
    sim::GreyImage grey;
    double next_frame = 0.05;
    for (double t = 0.0; t < kDurationS; t += 0.1) {
      std::vector<sim::SimDatagram> step;
      sim::SimOutputs out;
      out.on_datagram = [&](sim::SimDatagram&& d) { step.push_back(std::move(d)); };
      lidar->run(t, t + 0.1, scene, out);
      r.datagrams.push_back(std::move(step));
      std::vector<ImageFrame> frames;
      while (next_frame < t + 0.1) {
        const double tf = next_frame;
        next_frame += 1.0 / cam.params.rate_hz;
        const double exposure = camera.exposure_at(tf);
        camera.render(world, trajectory.at(tf).T_world_body() * cam.T_body_cam, exposure, rng,
                      grey);
        ImageFrame f;
        f.image = cv::Mat(grey.height, grey.width, CV_8UC1, grey.pixels.data()).clone();
        f.stamp.mapped = MappedTime::from_seconds(tf);
        f.exposure = from_seconds(exposure);
        set_exposure_times(f);
        frames.push_back(std::move(f));
      }
      r.frames.push_back(std::move(frames));
    }
    return r;
  }();
  return rec;
}

// FNV-1a-style mix of the bits of n doubles: the label's trajectory hash.
std::uint64_t mix(std::uint64_t hash, const double* v, int n) {
  for (int i = 0; i < n; ++i) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, v + i, sizeof bits);
    hash = (hash ^ bits) * 1099511628211ULL;
  }
  return hash;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

void run(benchmark::State& state, bool with_camera) {
  const Recording& rec = recording();
  const sim::LidarMount& mount = rec.scenario.lidars.at(0);
  std::vector<double> vio_wall, vio_cpu, vio_process_cpu, pyramid, selection, update, map, lio;
  std::vector<double> pyramid_cpu, selection_cpu, update_cpu, map_cpu, patches;
  std::uint64_t hash = 1469598103934665603ULL;
  for (auto _ : state) {
    daemon::WorkerPool pool(2);
    estimator::PipelineOptions po;
    po.T_imu_lidar = mount.T_body_sensor;
    po.runner = &pool;
    if (with_camera) {
      estimator::vio::VioCamera camera;
      camera.intrinsics = rec.scenario.cameras.at(0).params.intrinsics;
      camera.T_imu_cam = rec.scenario.cameras.at(0).T_body_cam;
      po.camera = camera;
    }
    estimator::LioPipeline pipeline(po);
    drivers::DecoderConfig config;
    config.model = "OS";
    config.metadata = rec.metadata;
    auto decoder = drivers::ouster::make_ouster_decoder(config);
    drivers::DecoderSinks sinks;
    sinks.on_scan = [&](const LidarScan& s) {
      LidarScan copy = s;
      copy.start.mapped = MappedTime(s.start.sensor.ns);
      pipeline.add_scan(std::move(copy));
    };
    sinks.on_imu = [&](const ImuSample& m) {
      ImuSample copy = m;
      copy.stamp.mapped = MappedTime(m.stamp.sensor.ns);
      pipeline.add_imu(copy);
    };
    for (std::size_t k = 0; k < rec.datagrams.size(); ++k) {
      for (const auto& d : rec.datagrams[k]) {
        decoder->on_packet({d.payload, d.host_time_ns, d.dst_port}, sinks);
      }
      if (with_camera) {
        for (const auto& f : rec.frames[k]) pipeline.add_image(f);
      }
      pipeline.process([&](const estimator::PipelineOutput& o) {
        const auto& t = o.report.timings;
        lio.push_back(t.total_ms - t.vio_ms);
        hash = mix(hash, o.x.p_world_imu.data(), 3);
        hash = mix(hash, o.x.R_world_imu.data(), 9);
        hash = mix(hash, &o.x.inv_exposure, 1);
        const auto& v = o.report.vio;
        if (!v.ran) return;
        vio_wall.push_back(v.timings.total_ms);
        vio_cpu.push_back(v.timings.cpu_ms);
        vio_process_cpu.push_back(v.timings.process_cpu_ms);
        pyramid.push_back(v.timings.pyramid_ms);
        selection.push_back(v.timings.selection_ms);
        update.push_back(v.timings.update_ms);
        map.push_back(v.timings.map_ms);
        pyramid_cpu.push_back(v.timings.pyramid_cpu_ms);
        selection_cpu.push_back(v.timings.selection_cpu_ms);
        update_cpu.push_back(v.timings.update_cpu_ms);
        map_cpu.push_back(v.timings.map_cpu_ms);
        patches.push_back(v.patches);
      });
    }
  }
  char label[40];
  std::snprintf(label, sizeof label, "trajectory %016llx", static_cast<unsigned long long>(hash));
  state.SetLabel(label);
  state.counters["lio_p50"] = percentile(lio, 0.5);
  state.counters["lio_p99"] = percentile(lio, 0.99);
  if (!with_camera) return;
  state.counters["images"] = static_cast<double>(vio_wall.size());
  state.counters["patches_p50"] = percentile(patches, 0.5);
  state.counters["vio_p50"] = percentile(vio_wall, 0.5);
  state.counters["vio_p99"] = percentile(vio_wall, 0.99);
  state.counters["vio_cpu_p50"] = percentile(vio_cpu, 0.5);
  state.counters["vio_cpu_p99"] = percentile(vio_cpu, 0.99);
  state.counters["vio_all_cpu_p50"] = percentile(vio_process_cpu, 0.5);
  state.counters["pyramid_p50"] = percentile(pyramid, 0.5);
  state.counters["selection_p50"] = percentile(selection, 0.5);
  state.counters["update_p50"] = percentile(update, 0.5);
  state.counters["map_p50"] = percentile(map, 0.5);
  state.counters["pyramid_cpu_p50"] = percentile(pyramid_cpu, 0.5);
  state.counters["selection_cpu_p50"] = percentile(selection_cpu, 0.5);
  state.counters["update_cpu_p50"] = percentile(update_cpu, 0.5);
  state.counters["map_cpu_p50"] = percentile(map_cpu, 0.5);
}

void BM_LivoRoom640x512(benchmark::State& state) {
  run(state, true);
}
void BM_LioOnlyRoom(benchmark::State& state) {
  run(state, false);
}

BENCHMARK(BM_LivoRoom640x512)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(1);
BENCHMARK(BM_LioOnlyRoom)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(1);

}  // namespace

BENCHMARK_MAIN();
