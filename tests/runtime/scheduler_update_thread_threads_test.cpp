// The filter update on its own thread (`livod run`, daemon/runtime/update_thread.hpp): the
// scheduler thread hands over one group at a time and holds what arrives meanwhile. Label
// "threads" (ThreadSanitizer in CI): the handover must be race-free, and it must not change what
// the estimator computes: the same recording through the update thread gives the same poses,
// bit for bit, as replay's single thread.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "daemon/replay/input_assignment.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/runtime/scheduler.hpp"
#include "daemon/runtime/update_thread.hpp"
#include "daemon/worker_pool.hpp"
#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

using daemon::runtime::UpdateThread;
using namespace std::chrono_literals;

void wait_until(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (!done() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(1ms);
}

TEST(UpdateThread, RunsTheJobOncePerStartAndRingsTheDoorbell) {
  int runs = 0;  // written by the job, read after done(): ordered by the handover
  drivers::capture::Doorbell bell;
  UpdateThread t([&] { ++runs; }, &bell);
  for (int i = 1; i <= 3; ++i) {
    const std::uint32_t token = bell.prepare();
    EXPECT_FALSE(t.busy());
    t.start();
    EXPECT_TRUE(t.busy());
    bell.wait(token, Nanoseconds(5'000'000'000));  // returns once rung
    wait_until([&] { return t.done(); });
    ASSERT_TRUE(t.done());
    t.collect();
    EXPECT_FALSE(t.busy());
    EXPECT_EQ(runs, i);
  }
  EXPECT_EQ(t.jobs(), 3U);
}

TEST(UpdateThread, CollectRethrowsWhatTheJobThrew) {
  bool fail = true;
  UpdateThread t(
      [&] {
        if (fail) throw std::runtime_error("map insertion failed");
      },
      nullptr);
  t.start();
  wait_until([&] { return t.done(); });
  EXPECT_THROW(t.collect(), std::runtime_error);
  fail = false;  // the thread is idle: no job reads it now
  t.start();
  EXPECT_NO_THROW(t.wait_and_collect());
}

TEST(UpdateThread, HeartbeatAdvancesWhileIdleAndStopsDuringALongJob) {
  std::atomic<bool> release{false};
  daemon::runtime::UpdateThreadOptions o;
  o.idle_beat = Nanoseconds(2'000'000);
  UpdateThread t(
      [&] {
        while (!release.load()) std::this_thread::sleep_for(1ms);
      },
      nullptr, o);
  const auto b0 = t.beats();
  wait_until([&] { return t.beats() >= b0 + 3; });
  EXPECT_GE(t.beats(), b0 + 3) << "an idle update thread must show it is alive";
  t.start();
  std::this_thread::sleep_for(20ms);  // the job has started and blocks
  const auto during = t.beats();
  std::this_thread::sleep_for(50ms);
  EXPECT_LE(t.beats(), during + 1) << "a thread stuck in its job must not look alive";
  release.store(true);
  t.wait_and_collect();
}

struct Pose {
  std::int64_t t_ns;
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

class PoseSink final : public daemon::runtime::OutputSink {
 public:
  void on_frame(const daemon::runtime::FrameOutput& f) override {
    poses.push_back(
        {f.estimate.t.ns, f.estimate.x.p_world_imu, Eigen::Quaterniond(f.estimate.x.R_world_imu)});
    if (f.estimate_sent) ++frames_after_estimate;
    // An estimate comes before its own frame, never after it nor for another one.
    EXPECT_EQ(estimates.size(), f.estimate_sent ? poses.size() : estimates.size());
  }
  void on_estimate(const daemon::runtime::EstimateOutput& e) override {
    EXPECT_EQ(e.index, poses.size()) << "the estimate of the frame that comes next";
    estimates.push_back(
        {e.estimate.t.ns, e.estimate.x.p_world_imu, Eigen::Quaterniond(e.estimate.x.R_world_imu)});
  }
  std::vector<Pose> estimates;
  std::size_t frames_after_estimate = 0;
  void on_imu_pose(const daemon::runtime::ImuPoseOutput& /*p*/) override { ++imu_poses; }
  [[nodiscard]] bool wants_imu_poses() const override { return true; }
  std::vector<Pose> poses;
  std::uint64_t imu_poses = 0;
};

std::vector<daemon::runtime::SensorInput> open_inputs(const daemon::LivodConfig& config) {
  const auto roles = daemon::runtime::assign_roles(config);
  const auto recordings = daemon::replay::assign_recordings(config, {});
  std::vector<daemon::runtime::SensorInput> inputs;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    if (!roles.unused_reason[i].empty() || !recordings[i]) continue;
    daemon::runtime::SensorInput in;
    in.sensor_index = i;
    in.source =
        daemon::replay::make_source(config.sensors[i], recordings[i]->replay, recordings[i]->ports);
    inputs.push_back(std::move(in));
  }
  return inputs;
}

TEST(SchedulerUpdateThread, GivesTheSamePosesAsTheSingleThreadedReplay) {
  const auto folder =
      test::simulate(sim::make_scenario("room_handheld_mid360"), 3.0, "update-thread");
  const daemon::LivodConfig config = test::load_clean_config(folder / "config.yaml");

  // Replay: one thread, every group as soon as it is due.
  PoseSink replay_sink;
  {
    daemon::WorkerPool pool(2);
    daemon::runtime::Scheduler s(config, open_inputs(config), &pool, replay_sink);
    while (!s.exhausted()) s.step();
    s.finish();
  }
  ASSERT_GE(replay_sink.poses.size(), 15U);

  // The daemon's way: one group per step on the update thread while events keep coming.
  PoseSink live_sink;
  drivers::capture::Doorbell bell;
  std::uint64_t jobs = 0;
  std::size_t early_estimates = 0;
  {
    daemon::WorkerPool pool(2);
    daemon::runtime::SchedulerOptions so;
    so.max_groups_per_step = 1;
    so.update_thread = true;
    so.update_doorbell = &bell;
    daemon::runtime::Scheduler s(config, open_inputs(config), &pool, live_sink, so);
    ASSERT_TRUE(s.has_update_thread());
    // A recording is not paced: left alone the loop would read it far faster than the filter
    // runs and the estimator's bounded queue would drop scans, as it does live when the filter
    // falls behind. Here up to 60 events (~50 ms of this rig's data) are held per update, then
    // the loop waits for it, as a sensor's pace would make it.
    std::size_t held = 0;
    std::size_t max_held = 0;
    // The pose of the running update handed out before the update (its map insertion) ended.
    const auto observe = [&] {
      if (s.update_running() && live_sink.estimates.size() > live_sink.poses.size()) {
        early_estimates = live_sink.estimates.size();
      }
    };
    while (!s.exhausted()) {
      const bool running = s.update_running();
      s.step();
      observe();
      const auto& status = s.estimator_status();  // health reads this between steps
      EXPECT_EQ(status.held_scans_dropped + status.held_imu_dropped, 0U);
      held = running && s.update_running() ? held + 1 : 0;
      max_held = std::max(max_held, held);
      if (held >= 60) {
        while (s.update_running()) {
          s.process_due();
          observe();
        }
        held = 0;
      }
    }
    s.finish();
    EXPECT_GT(max_held, 5U) << "no measurement arrived during an update: the test proves nothing";
    EXPECT_GT(s.update_beats(), 0U);
    jobs = s.stats().frames;
  }
  EXPECT_EQ(jobs, live_sink.poses.size());
  ASSERT_EQ(live_sink.poses.size(), replay_sink.poses.size());
  for (std::size_t i = 0; i < replay_sink.poses.size(); ++i) {
    const Pose& a = replay_sink.poses[i];
    const Pose& b = live_sink.poses[i];
    ASSERT_EQ(a.t_ns, b.t_ns) << "frame " << i;
    EXPECT_EQ(a.p, b.p) << "frame " << i;
    EXPECT_EQ(a.q.coeffs(), b.q.coeffs()) << "frame " << i;
  }
  // The daemon publishes each pose from the estimate handed out as soon as the update ended (before
  // the map insertion): one per frame, equal to the frame's, seen while updates still ran.
  EXPECT_TRUE(replay_sink.estimates.empty());
  ASSERT_EQ(live_sink.estimates.size(), live_sink.poses.size());
  EXPECT_EQ(live_sink.frames_after_estimate, live_sink.poses.size());
  for (std::size_t i = 0; i < live_sink.poses.size(); ++i) {
    EXPECT_EQ(live_sink.estimates[i].t_ns, live_sink.poses[i].t_ns) << "frame " << i;
    EXPECT_EQ(live_sink.estimates[i].p, live_sink.poses[i].p) << "frame " << i;
    EXPECT_EQ(live_sink.estimates[i].q.coeffs(), live_sink.poses[i].q.coeffs()) << "frame " << i;
  }
  EXPECT_GT(early_estimates, 0U) << "no pose left before its update's end";
  // IMU-rate poses keep coming whichever thread runs the update.
  EXPECT_GT(live_sink.imu_poses, 100U);
}

}  // namespace
}  // namespace livod
