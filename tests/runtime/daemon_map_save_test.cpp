// Map saves while the daemon runs, in-process, with LCM over memq:// (the real liblcm, no network):
// a paced replay of a simulated Mid-360 capture runs through the daemon's threads; the test is an
// operator's tool on the same LCM instance. A livod.command_t COMMAND_SAVE_MAP is answered on
// LIVOD_COMMAND_RESULT with a file that exists and holds the map so far, while poses keep coming;
// two requests sent while a save is being written are coalesced into it and both answered; an
// unknown command is rejected; SIGUSR1 to the daemon's thread saves a map announced on the same
// channel; the run ends with the recording, exit code 0.

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <thread>

#include "daemon/runtime/daemon.hpp"
#include "daemon/runtime/lcm_bus.hpp"
#include "lcmtypes/livod/command_result_t.hpp"
#include "lcmtypes/livod/command_t.hpp"
#include "lcmtypes/livod/pose_t.hpp"
#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

using namespace std::chrono_literals;

// What the daemon sends, received on its publisher thread (which dispatches memq messages).
struct Listener {
  std::mutex m;
  std::condition_variable cv;
  std::vector<livod::command_result_t> results;
  std::atomic<int> poses{0};

  void on_pose(const lcm::ReceiveBuffer* /*b*/, const std::string& /*c*/,
               const livod::pose_t* /*p*/) {
    ++poses;
  }
  void on_result(const lcm::ReceiveBuffer* /*b*/, const std::string& /*c*/,
                 const livod::command_result_t* r) {
    const std::lock_guard lock(m);
    results.push_back(*r);
    cv.notify_all();
  }
  // The first result matching `pred`, waiting up to `timeout`.
  template <class Pred>
  std::optional<livod::command_result_t> wait_for(Pred pred, std::chrono::seconds timeout) {
    std::unique_lock lock(m);
    std::optional<livod::command_result_t> found;
    cv.wait_for(lock, timeout, [&] {
      for (const auto& r : results) {
        if (pred(r)) {
          found = r;
          return true;
        }
      }
      return false;
    });
    return found;
  }
};

livod::command_t command(std::int64_t id, std::int8_t what = livod::command_t::COMMAND_SAVE_MAP) {
  livod::command_t c;
  c.utime = 0;
  c.request_id = id;
  c.sender = "map-save-test";
  c.command = what;
  return c;
}

bool wait_until(const std::function<bool()>& done, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

TEST(DaemonMapSave, LcmCommandsAndSigusr1SaveTheMapWhileRunning) {
  const auto sim = test::simulate(sim::make_scenario("room_handheld_mid360"), 8.0, "map-save");
  daemon::LivodConfig config = test::load_clean_config(sim / "config.yaml");
  config.outputs.lcm.url = "memq://";
  config.health.period_s = 0.2;
  const auto out = test::temp_dir("map-save-out");
  daemon::runtime::LcmBus bus(config.outputs.lcm, config.body_frame);
  Listener listener;
  bus.lcm().subscribe("LIVOD_POSE", &Listener::on_pose, &listener);
  bus.lcm().subscribe("LIVOD_COMMAND_RESULT", &Listener::on_result, &listener);

  // Holds the second save in progress until the test has sent its two quick requests.
  std::mutex hold_m;
  std::condition_variable hold_cv;
  int saves_started = 0;
  bool hold_second = true;
  daemon::runtime::DaemonOptions options;
  options.paced_replay = true;
  options.bus = &bus;
  options.out_dir = out;
  options.map_save_hook = [&] {
    std::unique_lock lock(hold_m);
    ++saves_started;
    hold_cv.notify_all();
    if (saves_started == 2) hold_cv.wait(lock, [&] { return !hold_second; });
  };
  const pthread_t daemon_thread = pthread_self();

  std::optional<livod::command_result_t> first;
  std::optional<livod::command_result_t> second;
  std::optional<livod::command_result_t> third;
  std::optional<livod::command_result_t> rejected;
  std::optional<livod::command_result_t> by_signal;
  int poses_at_first = 0;
  int poses_after_first = 0;
  std::jthread operator_tool([&](const std::stop_token&) {
    ASSERT_TRUE(wait_until([&] { return listener.poses >= 10; }, 20s)) << "no poses";
    const livod::command_t c1 = command(100);
    bus.lcm().publish("LIVOD_COMMAND", &c1);
    first = listener.wait_for([](const auto& r) { return r.request_id == 100; }, 10s);
    poses_at_first = listener.poses;
    // Two quick requests: the first starts a save (held by the hook), the second joins it.
    const livod::command_t c2 = command(200);
    bus.lcm().publish("LIVOD_COMMAND", &c2);
    {
      std::unique_lock lock(hold_m);
      hold_cv.wait_for(lock, 10s, [&] { return saves_started >= 2; });
    }
    const livod::command_t c3 = command(201);
    bus.lcm().publish("LIVOD_COMMAND", &c3);
    std::this_thread::sleep_for(400ms);  // the publisher polls LCM at least every 100 ms
    {
      const std::lock_guard lock(hold_m);
      hold_second = false;
    }
    hold_cv.notify_all();
    second = listener.wait_for([](const auto& r) { return r.request_id == 200; }, 10s);
    third = listener.wait_for([](const auto& r) { return r.request_id == 201; }, 10s);
    const livod::command_t bad = command(300, 42);
    bus.lcm().publish("LIVOD_COMMAND", &bad);
    rejected = listener.wait_for([](const auto& r) { return r.request_id == 300; }, 10s);
    pthread_kill(daemon_thread, SIGUSR1);
    by_signal = listener.wait_for([](const auto& r) { return r.requested_by == "SIGUSR1"; }, 10s);
  });
  const auto r = daemon::runtime::run_daemon(config, options);
  operator_tool.join();
  poses_after_first = listener.poses - poses_at_first;

  ASSERT_EQ(r.exit_code, 0) << (r.errors.empty() ? "" : r.errors.front());
  EXPECT_EQ(r.stopped_by, "end of the recordings");
  ASSERT_TRUE(first.has_value()) << "no answer to the first command";
  EXPECT_EQ(first->status, livod::command_result_t::STATUS_OK) << first->message;
  EXPECT_EQ(first->requested_by, "map-save-test");
  EXPECT_FALSE(first->coalesced);
  EXPECT_GT(first->points, 0);
  EXPECT_EQ(std::filesystem::path(first->path).parent_path(),
            std::filesystem::absolute(out) / "maps");
  ASSERT_TRUE(std::filesystem::exists(first->path));
  EXPECT_EQ(static_cast<std::uintmax_t>(first->bytes), std::filesystem::file_size(first->path));

  ASSERT_TRUE(second.has_value() && third.has_value()) << "the quick requests were not answered";
  EXPECT_EQ(second->status, livod::command_result_t::STATUS_OK) << second->message;
  EXPECT_FALSE(second->coalesced);
  EXPECT_TRUE(third->coalesced);
  EXPECT_EQ(third->status, livod::command_result_t::STATUS_OK) << third->message;
  EXPECT_EQ(third->path, second->path);
  EXPECT_EQ(second->save_number, 2);
  EXPECT_EQ(third->save_number, 2);
  EXPECT_NE(second->path, first->path);
  EXPECT_GE(second->points, first->points);  // the map grew meanwhile (or stayed)

  ASSERT_TRUE(rejected.has_value());
  EXPECT_EQ(rejected->status, livod::command_result_t::STATUS_REJECTED);
  ASSERT_TRUE(by_signal.has_value()) << "SIGUSR1 saved nothing";
  EXPECT_EQ(by_signal->status, livod::command_result_t::STATUS_OK) << by_signal->message;
  EXPECT_EQ(by_signal->save_number, 3);
  EXPECT_TRUE(std::filesystem::exists(by_signal->path));

  // The run went on while saving: poses after the first save (it came about 1 s into the 8 s
  // capture, at 10 scans per second).
  EXPECT_GT(poses_after_first, 40);
  EXPECT_EQ(r.publisher.map_saves.saved, 3U);
  EXPECT_EQ(r.publisher.map_saves.coalesced, 1U);
  EXPECT_EQ(r.publisher.map_saves.rejected, 1U);
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(out / "maps")) {
    EXPECT_EQ(e.path().extension(), ".pcd") << e.path();
    ++files;
  }
  EXPECT_EQ(files, 3U);
  std::printf("[map-save] first save %lld points in %.3f s; %d poses after it\n",
              static_cast<long long>(first->points), first->duration_s, poses_after_first);
}

}  // namespace
}  // namespace livod
