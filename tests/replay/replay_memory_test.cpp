// Bounded memory over a long drive: the OS1-128 street scenario stretched to 650 m (65 s at
// 10 m/s, longer than the 100 m box the sliding map keeps). The estimator's map must stop growing
// once the box is full (its bytes flat after warm-up, voxels removed by sliding), the exported map
// must stay within its point budget, and the process's resident memory must stop growing with it.
// The 15-minute version of this check is bench/replay_bench.sh (docs/replay.md reports it): it does
// not fit the CI time budget.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

struct FrameRow {
  double t = 0.0;
  double map_bytes = 0.0;
  double exported = 0.0;
  double rss = 0.0;
};

std::vector<FrameRow> read_frames(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) header.push_back(f);
  }
  auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t t = column("t");
  const std::size_t bytes = column("map_bytes");
  const std::size_t exported = column("exported_points");
  const std::size_t rss = column("rss_bytes");
  std::vector<FrameRow> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string v; std::getline(ss, v, ',');) f.push_back(v);
    rows.push_back({std::stod(f.at(t)), std::stod(f.at(bytes)), std::stod(f.at(exported)),
                    std::stod(f.at(rss))});
  }
  return rows;
}

// Largest value of `field` over rows [begin, end) of the run (fractions of the frame count).
template <class Field>
double peak(const std::vector<FrameRow>& rows, double begin, double end, Field field) {
  const auto n = static_cast<double>(rows.size());
  double best = 0.0;
  for (auto i = static_cast<std::size_t>(begin * n); i < static_cast<std::size_t>(end * n); ++i) {
    best = std::max(best, field(rows[i]));
  }
  return best;
}

TEST(ReplayMemory, LongDriveStaysBounded) {
  sim::Scenario scenario = sim::make_scenario("street_vehicle_os1_128");
  if (!test::scenario_runnable(scenario)) GTEST_SKIP() << "OS1-128 is not simulated yet";
  scenario.street_length_m = 720.0;
  const auto folder = test::simulate(scenario, 65.0, "memory");
  const auto config =
      test::with_estimator(folder, "{lio: {point_filter_num: 4, filter_size_surf: 0.5}}");
  daemon::replay::ReplayOptions options;
  options.out_dir = test::temp_dir("memory-replay");
  options.map_max_points = 150'000;  // small, so that the budget is reached within the drive
  const auto result = daemon::replay::run_replay(test::load_clean_config(config), options);
  const auto& s = result.summary;
  const auto rows = read_frames(result.frames_csv);
  ASSERT_GT(rows.size(), 600U);

  const auto bytes = [](const FrameRow& r) { return r.map_bytes; };
  const auto rss = [](const FrameRow& r) { return r.rss; };
  // 0-30 %: 0-200 m, the box fills; then the map slides.
  const double warm = peak(rows, 0.30, 0.55, bytes);
  const double late = peak(rows, 0.75, 1.0, bytes);
  const double rss_warm = peak(rows, 0.30, 0.55, rss);
  const double rss_late = peak(rows, 0.75, 1.0, rss);
  std::printf(
      "[memory] %zu frames: map bytes peak 30-55 %% %.2f MiB, 75-100 %% %.2f MiB; removed voxels "
      "%llu; exported %zu points (%llu dropped); RSS peak 30-55 %% %.1f MiB, 75-100 %% %.1f MiB, "
      "process peak %.1f MiB\n",
      rows.size(), warm / 1048576.0, late / 1048576.0,
      static_cast<unsigned long long>(s.map.removed_voxels), s.exported_points,
      static_cast<unsigned long long>(s.exported_dropped), rss_warm / 1048576.0,
      rss_late / 1048576.0, static_cast<double>(s.peak_rss_bytes) / 1048576.0);
  EXPECT_GT(s.map.removed_voxels, 1000U);
  EXPECT_LT(late, 1.2 * warm) << "the estimator's map keeps growing";
  EXPECT_LE(s.exported_points, options.map_max_points);
  EXPECT_GT(s.exported_dropped, 0U);
  EXPECT_LT(rss_late, rss_warm + 16.0 * 1048576.0) << "resident memory keeps growing";
}

}  // namespace
}  // namespace livod
