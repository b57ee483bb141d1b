// The camera capture path at 1280x1024 mono8, 30 Hz, through an Aravis fake camera:
//   camera -> Aravis stream thread -> livod capture thread (pop, copy into the ring slot, push
//   back) -> FrameRing -> consumer thread (poll: clock mapping, callback)
// Reports, over --seconds of streaming:
//   * the CPU time of livod's capture thread (from /proc/self/task/<tid>/stat) as % of one core,
//     and per frame;
//   * frame latency, buffer timestamp -> host ring (FrameInfo::ring_push): p50, p99, max. Both
//     Aravis fakes stamp frames with the host's CLOCK_REALTIME when they fill them, so the
//     latency is ring_push - (buffer timestamp converted to CLOCK_MONOTONIC): everything from the
//     end of the (simulated) exposure to the frame being in the ring;
//   * the part of it from Aravis's system timestamp (host_rx: the in-process fake stamps both at
//     once; for GigE, when the frame's leader packet arrived) to the ring;
//   * frames delivered, incomplete, lost (block-id gaps), ring overruns.
//
//   ./camera_capture_bench [--seconds S] [--gv] [--rt PRIO]
//
// --gv: the GigE Vision simulator (arv-fake-gv-camera-0.8) over loopback in a private network
// namespace (needs root: unshare); default: Aravis's in-process fake camera. A program rather
// than a Google Benchmark loop: it measures a multi-thread steady state.

#include <benchmark/benchmark.h>
#include <dirent.h>
#include <fcntl.h>
#include <net/if.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/realtime_offset.hpp"
#include "drivers/camera/aravis_camera.hpp"
#include "drivers/camera/camera_source.hpp"

extern char** environ;

namespace {

using namespace std::chrono_literals;
using livod::camera::CameraFrame;

// utime + stime of the thread named `name` (the capture thread names itself), in seconds.
double thread_cpu_s(const std::string& name) {
  DIR* dir = opendir("/proc/self/task");
  if (dir == nullptr) return -1.0;
  const double tick = static_cast<double>(sysconf(_SC_CLK_TCK));
  double cpu = -1.0;
  while (dirent* e = readdir(dir)) {
    if (e->d_name[0] == '.') continue;
    const std::string base = std::string("/proc/self/task/") + e->d_name;
    std::ifstream comm(base + "/comm");
    std::string n;
    std::getline(comm, n);
    if (n != name) continue;
    std::ifstream stat(base + "/stat");
    std::string line;
    std::getline(stat, line);
    // Fields after the ")" of the command: state is field 3; utime, stime are 14 and 15.
    std::istringstream rest(line.substr(line.rfind(')') + 2));
    std::string field;
    double utime = 0;
    double stime = 0;
    for (int i = 3; i <= 15 && rest >> field; ++i) {
      if (i == 14) utime = std::stod(field);
      if (i == 15) stime = std::stod(field);
    }
    cpu = (utime + stime) / tick;
  }
  closedir(dir);
  return cpu;
}

void loopback_namespace() {
  if (unshare(CLONE_NEWNET) != 0) {
    std::perror("unshare(CLONE_NEWNET) (run as root)");
    std::exit(1);
  }
  const int s = socket(AF_INET, SOCK_DGRAM, 0);
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
  ioctl(s, SIOCGIFFLAGS, &ifr);
  ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP);
  ioctl(s, SIOCSIFFLAGS, &ifr);
  close(s);
}

pid_t start_gv_fake() {
  const char* argv[] = {"arv-fake-gv-camera-0.8", "-i", "127.0.0.1", "-s", "GV01", nullptr};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  if (posix_spawnp(&pid, argv[0], &actions, nullptr, const_cast<char* const*>(argv), environ) !=
      0) {
    std::perror("arv-fake-gv-camera-0.8");
    std::exit(1);
  }
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5)];
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 20.0;
  bool gv = false;
  int rt = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seconds" && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else if (a == "--gv")
      gv = true;
    else if (a == "--rt" && i + 1 < argc)
      rt = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--seconds S] [--gv] [--rt PRIO]\n", argv[0]);
      return 2;
    }
  }
  pid_t fake = -1;
  livod::camera::AravisCameraConfig cfg;
  if (gv) {
    loopback_namespace();
    fake = start_gv_fake();
    cfg.camera_id = "Aravis-Fake-GV01";
  } else {
    livod::camera::AravisCamera::enable_fake_interface();
    cfg.camera_id = "Fake_1";
  }
  cfg.width = 1280;
  cfg.height = 1024;
  cfg.frame_rate_hz = 30.0;
  cfg.buffers = 8;
  livod::camera::CameraSourceConfig sc;
  sc.name = "bench";
  sc.width = 1280;
  sc.height = 1024;
  sc.ring_capacity = 8;
  sc.thread.thread_name = "cam:bench";
  if (rt > 0) sc.thread.realtime_priority = rt;
  std::unique_ptr<livod::camera::CameraSource> source;
  for (int attempt = 0; !source; ++attempt) {
    try {
      source = std::make_unique<livod::camera::CameraSource>(
          sc, std::make_unique<livod::camera::AravisCamera>(cfg));
    } catch (const std::exception& e) {
      if (attempt > 50) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
      }
      std::this_thread::sleep_for(200ms);
    }
  }
  livod::RealtimeToMonotonic realtime;
  std::vector<double> latency_ms;
  std::vector<double> rx_latency_ms;
  std::size_t frames = 0;
  const auto cb = [&](const CameraFrame& f) {
    ++frames;
    const auto stamped = realtime.to_host(f.info.sensor_time.ns);
    latency_ms.push_back(static_cast<double>(f.info.ring_push.ns - stamped.ns) * 1e-6);
    rx_latency_ms.push_back(static_cast<double>(f.info.ring_push.ns - f.info.host_rx.ns) * 1e-6);
    benchmark::DoNotOptimize(f.image.data);
  };
  // Warm-up (first frames, clock fit), then the measured window.
  const auto warm = std::chrono::steady_clock::now() + 2s;
  while (std::chrono::steady_clock::now() < warm) {
    source->poll(cb);
    std::this_thread::sleep_for(2ms);
  }
  latency_ms.clear();
  rx_latency_ms.clear();
  frames = 0;
  const auto c0 = source->backend_counters();
  const std::size_t over0 = source->ring_overruns();
  const double cpu0 = thread_cpu_s("cam:bench");
  const auto t0 = std::chrono::steady_clock::now();
  const auto end = t0 + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    source->poll(cb);
    std::this_thread::sleep_for(2ms);
    realtime.refresh();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu = thread_cpu_s("cam:bench") - cpu0;
  const auto c1 = source->backend_counters();
  source->stop();
  if (fake > 0) {
    kill(fake, SIGKILL);
    waitpid(fake, nullptr, 0);
  }
  std::printf("camera_capture_bench: %s, 1280x1024 mono8 @ 30 Hz, %.1f s\n",
              gv ? "GigE Vision simulator over loopback (arv-fake-gv-camera-0.8)"
                 : "Aravis in-process fake camera",
              wall);
  std::printf(
      "  frames delivered %zu (%.2f/s), incomplete %llu, lost (id gaps) %llu, ring "
      "overruns %zu\n",
      frames, static_cast<double>(frames) / wall,
      static_cast<unsigned long long>(c1.incomplete - c0.incomplete),
      static_cast<unsigned long long>(c1.sequence_gaps - c0.sequence_gaps),
      source->ring_overruns() - over0);
  std::printf("  capture thread CPU: %.2f %% of one core (%.3f ms per frame)\n", 100.0 * cpu / wall,
              frames > 0 ? 1e3 * cpu / static_cast<double>(frames) : 0.0);
  std::printf("  latency buffer timestamp -> ring: p50 %.3f ms, p99 %.3f ms, max %.3f ms\n",
              percentile(latency_ms, 0.5), percentile(latency_ms, 0.99),
              latency_ms.empty() ? 0.0 : *std::max_element(latency_ms.begin(), latency_ms.end()));
  std::printf("  of which Aravis system timestamp (host_rx) -> ring: p50 %.3f ms, p99 %.3f ms\n",
              percentile(rx_latency_ms, 0.5), percentile(rx_latency_ms, 0.99));
  double load[3] = {0, 0, 0};
  if (getloadavg(load, 3) > 0) std::printf("  load average %.1f\n", load[0]);
  return 0;
}
