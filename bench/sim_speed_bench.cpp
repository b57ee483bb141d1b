// Real-time factor of the simulator on one core: simulated seconds per CPU second (process CPU
// time, so a helper thread could not hide work) of
//   (a) a Livox Avia (points + internal IMU) and one 640x512 camera in the room,
//   (b) an Ouster OS1-64 (points + internal IMU) and one 640x512 camera in the room,
// per component (LiDAR to wire-format datagrams, camera rendering) and end to end through the
// runner (every file written, images included; without PNG files; with the bag). PNG encoding
// costs the difference between the first two runner rows minus rendering. The goal is >= 1x for
// (b), end to end.
//
//   sim_speed_bench [--seconds S]     (default 4 s of simulated time per measurement, moving)
//
// A report program rather than Google Benchmark cases: each measurement is one long run whose
// figure is a ratio of times, printed as a table for docs/simulator.md.

#include <time.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "tools/sim/camera_sim.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/runner.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/worlds.hpp"

namespace {

using livod::sim::Scenario;

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

struct Row {
  std::string what;
  double simulated_s = 0.0;
  double cpu_s = 0.0;
};

void print(const std::vector<Row>& rows) {
  std::printf("%-58s %8s %8s %10s\n", "measurement", "sim s", "cpu s", "x realtime");
  for (const auto& r : rows) {
    std::printf("%-58s %8.2f %8.3f %10.2f\n", r.what.c_str(), r.simulated_s, r.cpu_s,
                r.simulated_s / r.cpu_s);
  }
}

// The scenario's first LiDAR from t0 for `seconds`, datagrams discarded after encoding.
Row lidar_only(const Scenario& s, const livod::sim::World& world, double t0, double seconds) {
  const livod::sim::Trajectory trajectory(s.trajectory);
  const auto& mount = s.lidars.at(0);
  livod::sim::SimLidarOptions o;
  o.range = mount.range;
  o.clock = mount.clock;
  o.link = mount.link;
  o.imu_noise = mount.imu_noise;
  auto lidar = livod::sim::make_sim_lidar(mount.model, o);
  livod::sim::SceneContext scene{&world, &trajectory, mount.T_body_sensor};
  std::size_t bytes = 0;
  livod::sim::SimOutputs out;
  out.on_datagram = [&bytes](livod::sim::SimDatagram&& d) { bytes += d.payload.size(); };
  const double start = cpu_seconds();
  for (double t = t0; t < t0 + seconds; t += 0.5) lidar->run(t, t + 0.5, scene, out);
  const double cpu = cpu_seconds() - start;
  if (bytes == 0) std::fprintf(stderr, "no datagrams?\n");
  return {s.name + ": LiDAR " + mount.model + " + IMU -> datagrams", seconds, cpu};
}

// The scenario's first camera at its rate, rendering only.
Row camera_only(const Scenario& s, const livod::sim::World& world, double t0, double seconds) {
  const livod::sim::Trajectory trajectory(s.trajectory);
  const auto& cam = s.cameras.at(0);
  const livod::sim::CameraSim sim(cam.params);
  std::mt19937_64 rng(1);
  livod::sim::GreyImage img;
  const double period = 1.0 / cam.params.rate_hz;
  const double start = cpu_seconds();
  for (double t = t0 + period / 2; t < t0 + seconds; t += period) {
    sim.render(world, trajectory.at(t).T_world_body() * cam.T_body_cam, sim.exposure_at(t), rng,
               img);
  }
  const double cpu = cpu_seconds() - start;
  const auto& k = cam.params.intrinsics;
  return {s.name + ": camera " + std::to_string(k.width) + "x" + std::to_string(k.height) +
              " render @ " + std::to_string(static_cast<int>(cam.params.rate_hz)) + " Hz",
          seconds, cpu};
}

Row runner(const Scenario& s, double seconds, bool images, bool bag) {
  livod::sim::SimRunOptions o;
  o.out_dir = std::filesystem::temp_directory_path() / ("livod_sim_speed_" + s.name);
  o.duration_s = seconds;
  o.write_images = images;
  o.write_bag = bag;
  std::filesystem::remove_all(o.out_dir);
  const double start = cpu_seconds();
  livod::sim::run_scenario(s, o);
  const double cpu = cpu_seconds() - start;
  std::filesystem::remove_all(o.out_dir);
  std::string what = s.name + ": runner, all files";
  if (!images) what += ", no PNG";
  if (bag) what += " + sequence.bag";
  return {what, seconds, cpu};
}

bool simulated(const std::string& model) {
  for (const auto& [m, _] : livod::sim::simulated_lidar_models()) {
    if (m == model) return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 4.0;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--seconds") == 0) seconds = std::stod(argv[i + 1]);
  }
  // Measured while moving (after the scenarios' 2 s standstill + 2 s ramp).
  constexpr double kMoving = 4.0;
  std::vector<Row> rows;
  const livod::sim::World room = livod::sim::make_room_world(1);
  for (const char* name : {"room_handheld_avia", "room_handheld_os1_64"}) {
    const Scenario s = livod::sim::make_scenario(name);
    if (!simulated(s.lidars.at(0).model)) {
      std::printf("%s: the %s model is not simulated yet\n", name, s.lidars[0].model.c_str());
      continue;
    }
    rows.push_back(lidar_only(s, room, kMoving, seconds));
    rows.push_back(camera_only(s, room, kMoving, seconds));
    // The runner starts at t = 0 (standstill included) and writes everything.
    rows.push_back(runner(s, seconds, true, false));
    rows.push_back(runner(s, seconds, false, false));
    rows.push_back(runner(s, seconds, true, true));
  }
  print(rows);
  return 0;
}
