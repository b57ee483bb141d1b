// Voxel-grid downsampling keeps one measured point per cell (chosen by a hash of its coordinates,
// blind to its noise), and the point budget adapts the cell to the points a scan brings.

#include "estimator/lio/downsample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "estimator/lio/point_budget.hpp"
#include "estimator/lio/point_filter.hpp"

namespace livod::estimator {
namespace {

std::tuple<long, long, long> cell_of(const Eigen::Vector3d& p, double cell) {
  return {static_cast<long>(std::floor(p.x() / cell)), static_cast<long>(std::floor(p.y() / cell)),
          static_cast<long>(std::floor(p.z() / cell))};
}

TEST(VoxelGridDownsampler, KeepsOneMeasuredPointPerCellInFirstAppearanceOrder) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 5000; ++i) points.emplace_back(u(rng), u(rng), 0.3 * u(rng));
  const std::vector<Eigen::Vector3d> input = points;
  VoxelGridDownsampler ds(0.5);
  ds.apply(points);
  std::set<std::tuple<long, long, long>> cells;
  for (const auto& p : input) cells.insert(cell_of(p, 0.5));
  ASSERT_EQ(points.size(), cells.size());
  std::set<std::tuple<long, long, long>> seen;
  std::size_t last_first = 0;
  for (const auto& p : points) {
    // A measured point, not a centroid.
    const auto it = std::find(input.begin(), input.end(), p);
    ASSERT_NE(it, input.end());
    EXPECT_TRUE(seen.insert(cell_of(p, 0.5)).second) << "two points from one cell";
    // Cells come in the order of their first point.
    const auto first = static_cast<std::size_t>(
        std::find_if(input.begin(), input.end(),
                     [&](const Eigen::Vector3d& q) { return cell_of(q, 0.5) == cell_of(p, 0.5); }) -
        input.begin());
    EXPECT_GE(first + 1, last_first + 1);
    last_first = first;
  }
  // apply(in, out) gives the same and leaves its input alone.
  std::vector<Eigen::Vector3d> out;
  ds.apply(input, out);
  EXPECT_EQ(out, points);
}

// The defect it fixes: a cell holding a corner (two walls) or a thin pole gave a centroid inside
// the solid, off every surface, at a place that depends on how the viewpoint samples the cell.
// The kept point lies on the surface.
TEST(VoxelGridDownsampler, KeptPointLiesOnTheSurfaceAtACorner) {
  std::vector<Eigen::Vector3d> points;
  // An inside corner of two walls x = 0.2 and y = 0.2 within the cell [0, 1)^3, sampled more
  // densely on one wall (as from a viewpoint facing it).
  for (int i = 0; i < 40; ++i) {
    for (int k = 0; k < 5; ++k) points.emplace_back(0.2, 0.2 + 0.02 * i, 0.1 + 0.2 * k);
  }
  for (int i = 0; i < 10; ++i) {
    for (int k = 0; k < 5; ++k) points.emplace_back(0.2 + 0.08 * i, 0.2, 0.1 + 0.2 * k);
  }
  VoxelGridDownsampler ds(1.0);
  ds.apply(points);
  ASSERT_EQ(points.size(), 1U);
  const Eigen::Vector3d& p = points[0];
  EXPECT_TRUE(p.x() == 0.2 || p.y() == 0.2) << p.transpose();
}

// On a noisy plane the kept points are as likely above as below it: the choice must not favour
// one side.
TEST(VoxelGridDownsampler, UnbiasedOnANoisyPlane) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 20.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  double sum = 0.0;
  std::size_t n = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::Vector3d> points;
    // The plane z = 0.13 crosses its cells off their middle.
    for (int i = 0; i < 20000; ++i) points.emplace_back(u(rng), u(rng), 0.13 + noise(rng));
    VoxelGridDownsampler ds(0.5);
    ds.apply(points);
    for (const auto& p : points) sum += p.z() - 0.13;
    n += points.size();
  }
  // The mean is zero within a few standard errors (of the noise: the kept point is any of its
  // cell's).
  EXPECT_LT(std::abs(sum / static_cast<double>(n)), 4.0 * 0.02 / std::sqrt(static_cast<double>(n)));
}

// LiDAR noise lies along the ray, and the rays cross the ground at a slant: a point the noise
// moved down also moved away from the sensor. A rule that chose by position along the ray (the
// lowest, the nearest to the sensor) would keep points off the ground on average; the kept points'
// height error must average to zero as that of all points does. (The street drive's tilt under
// the nearest-to-centroid rule needs the whole scene: it is checked by the long drives,
// long_run_memory_test.cpp and long_drive_test.cpp.)
TEST(VoxelGridDownsampler, UnbiasedWithRangeNoiseAlongSlantedRays) {
  std::mt19937 rng(13);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  constexpr double kHeight = 1.8;  // sensor above the ground z = 0
  constexpr double kCell = 0.15;
  double sum = 0.0;
  double sum2 = 0.0;
  std::size_t n = 0;
  for (int scan = 0; scan < 12; ++scan) {
    // The sensor moves between scans, so the rings cross the grid at other places.
    const Eigen::Vector3d sensor(kCell * phase(rng), kCell * phase(rng), kHeight);
    std::vector<Eigen::Vector3d> points;
    for (int ring = 0; ring < 32; ++ring) {
      const double down = (4.0 + 0.6 * ring) * 3.14159265358979 / 180.0;  // 4 to 22.6 deg
      for (int col = 0; col < 2048; ++col) {
        const double azimuth = 2.0 * 3.14159265358979 * col / 2048.0;
        const Eigen::Vector3d ray(std::cos(down) * std::cos(azimuth),
                                  std::cos(down) * std::sin(azimuth), -std::sin(down));
        const double range = kHeight / std::sin(down);
        points.push_back(sensor + (range + noise(rng)) * ray);
      }
    }
    VoxelGridDownsampler ds(kCell);
    ds.apply(points);
    for (const auto& p : points) {
      sum += p.z();
      sum2 += p.z() * p.z();
    }
    n += points.size();
  }
  const double mean = sum / static_cast<double>(n);
  const double sd = std::sqrt(sum2 / static_cast<double>(n) - mean * mean);
  EXPECT_LT(std::abs(mean), 4.0 * sd / std::sqrt(static_cast<double>(n)))
      << "mean height error " << mean << " m, sd " << sd << " m, " << n << " points";
}

// The kept points are a function of the set of points, not of their order: the same scan
// delivered by another container, or cut at another packet, keeps the same points. Equal ranks
// (points within the quantum of each other) are decided by the coordinates, not by which point
// came first.
TEST(VoxelGridDownsampler, SelectionDoesNotDependOnThePointOrder) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 20000; ++i) points.emplace_back(u(rng), u(rng), 0.5 * u(rng));
  // A cell whose eight points differ by less than the quantum: all of equal rank.
  for (const double x : {0.0, 1e-6}) {
    for (const double y : {0.0, 1e-6}) {
      for (const double z : {0.0, 1e-6}) points.emplace_back(10.25 + x, 10.25 + y, 0.25 + z);
    }
  }
  const auto kept_set = [](std::vector<Eigen::Vector3d> p) {
    VoxelGridDownsampler ds(0.5);
    ds.apply(p);
    std::set<std::tuple<double, double, double>> s;
    for (const auto& q : p) s.insert({q.x(), q.y(), q.z()});
    return s;
  };
  const auto reference = kept_set(points);
  EXPECT_TRUE(reference.contains({10.25, 10.25, 0.25}));  // the smallest of the tied points
  for (int trial = 0; trial < 5; ++trial) {
    std::shuffle(points.begin(), points.end(), rng);
    EXPECT_EQ(kept_set(points), reference) << "order " << trial;
  }
  // Reversed, too (the tied point that came first before now comes last).
  std::reverse(points.begin(), points.end());
  EXPECT_EQ(kept_set(points), reference);
}

// select() keeps the same points as apply(), as indices of the caller's points.
TEST(VoxelGridDownsampler, SelectKeepsTheIndicesOfTheSamePoints) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::vector<Eigen::Vector3d> points;
  std::vector<std::uint32_t> indices;
  for (int i = 0; i < 3000; ++i) {
    points.emplace_back(u(rng), u(rng), u(rng));
    indices.push_back(static_cast<std::uint32_t>(7 * i + 1));  // the caller's numbering
  }
  VoxelGridDownsampler ds(0.4);
  std::vector<Eigen::Vector3d> applied;
  ds.apply(points, applied);
  ds.select(points, indices);
  ASSERT_EQ(indices.size(), applied.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    EXPECT_EQ(points[(indices[k] - 1) / 7], applied[k]) << k;
  }
}

// A scan of a flat area: points on a plane, count falling as 1 / cell^2.
std::vector<Eigen::Vector3d> plane_scan(double side, double spacing) {
  std::vector<Eigen::Vector3d> points;
  for (double x = 0.0; x < side; x += spacing) {
    for (double y = 0.0; y < side; y += spacing) points.emplace_back(x, y, 0.05 * std::sin(x));
  }
  return points;
}

TEST(PointBudget, ConvergesToTheBudgetAndStaysWithinTheCellLimits) {
  const auto scan = plane_scan(60.0, 0.1);  // 360 k points, 3.6 k cells of 1 m
  PointBudget budget(8000, 0.1, 1.0);
  VoxelGridDownsampler ds(budget.cell());
  std::vector<Eigen::Vector3d> out;
  std::size_t kept = 0;
  for (int k = 0; k < 15; ++k) {
    ds.set_cell(budget.cell());
    ds.apply(scan, out);
    if (budget.observe(out.size())) {
      ds.set_cell(budget.cell());
      ds.apply(scan, out);
      budget.observe(out.size());
    }
    kept = out.size();
  }
  EXPECT_NEAR(static_cast<double>(kept), 8000.0, 0.2 * 8000.0);
  EXPECT_GT(budget.cell(), 0.1);
  EXPECT_LT(budget.cell(), 1.0);
  // A small scene cannot fill the budget: the cell stays at its minimum.
  const auto small = plane_scan(5.0, 0.1);
  PointBudget room(8000, 0.1, 1.0);
  for (int k = 0; k < 5; ++k) {
    ds.set_cell(room.cell());
    ds.apply(small, out);
    room.observe(out.size());
  }
  EXPECT_DOUBLE_EQ(room.cell(), 0.1);
  // A huge one is capped at the largest cell.
  PointBudget street(100, 0.1, 0.5);
  for (int k = 0; k < 10; ++k) {
    ds.set_cell(street.cell());
    ds.apply(scan, out);
    street.observe(out.size());
  }
  EXPECT_DOUBLE_EQ(street.cell(), 0.5);
}

TEST(PointBudget, AskForARedoOnlyWhenFarOverAndAbleToGrow) {
  PointBudget b(1000, 0.1, 1.0);
  EXPECT_FALSE(b.observe(1100));  // within 15 %: no change
  EXPECT_DOUBLE_EQ(b.cell(), 0.1);
  EXPECT_FALSE(b.observe(1400));  // over, but not by half: next scan
  EXPECT_GT(b.cell(), 0.1);
  EXPECT_TRUE(b.observe(9000));  // far over: redo this one
  PointBudget capped(1000, 0.5, 0.5);
  EXPECT_FALSE(capped.observe(9000));  // cannot grow: redoing would not help
}

// The cell is always a step of the ladder min x 2^(k/8), and counts that differ by a few points
// (another container, another scan cut) give the same cell.
// Several LiDARs: an update's count is scaled to the budget's span, and an update under a quarter
// of it (the few points after scans that ended together) leaves the cell alone.
TEST(PointBudget, PartsAreScaledToTheBudgetsSpanAndSliversIgnored) {
  PointBudget whole(1000, 0.1, 1.0);
  PointBudget part(1000, 0.1, 1.0);
  whole.observe(4000);
  part.observe_part(8000, 2.0);  // two spans' worth: the same count per span
  EXPECT_DOUBLE_EQ(part.cell(), whole.cell());
  EXPECT_GT(part.cell(), 0.1);
  const double cell = part.cell();
  part.observe_part(3, 0.001);  // a sliver: not counted
  EXPECT_DOUBLE_EQ(part.cell(), cell);
  part.observe_part(10, 0.3);  // short but counted: 33 per span, far under the budget
  EXPECT_LT(part.cell(), cell);
}

TEST(PointBudget, CellStaysOnTheLadderSoNearbyCountsGiveTheSameCell) {
  PointBudget a(8000, 0.1, 0.5);
  PointBudget b(8000, 0.1, 0.5);
  // The counts of a street drive entering a room and back, b's 0.5 % above a's.
  const std::vector<double> counts = {30000, 21000, 14000, 10500, 9000, 4000, 3000, 6000, 12000};
  for (const double c : counts) {
    a.observe(static_cast<std::size_t>(c));
    b.observe(static_cast<std::size_t>(c * 1.005));
    EXPECT_EQ(a.cell(), b.cell()) << c;
    const double steps = PointBudget::kStepsPerOctave * std::log2(a.cell() / 0.1);
    if (a.cell() < 0.5) {
      EXPECT_NEAR(steps, std::round(steps), 1e-9) << a.cell();
    }
    EXPECT_GE(a.cell(), 0.1);
    EXPECT_LE(a.cell(), 0.5);
  }
}

// point_filter_num by the point's own coordinates: about one point in n of every ring (the rings
// of a spinning LiDAR interleave, so every n-th point of the scan would drop whole rings), and the
// same points whatever their order in the scan.
TEST(PointFilter, KeepsOneInNOfEveryRingWhateverTheOrder) {
  constexpr int kRings = 32;
  constexpr int kColumns = 2000;
  constexpr std::uint32_t kN = 4;
  std::vector<std::vector<Eigen::Vector3f>> rings(kRings);
  std::vector<Eigen::Vector3f> scan;  // column by column: the rings interleave
  for (int c = 0; c < kColumns; ++c) {
    const double az = 2.0 * M_PI * c / kColumns;
    for (int r = 0; r < kRings; ++r) {
      const double el = (-15.0 + r) * M_PI / 180.0;
      const double range = 12.0 + 0.5 * std::sin(3.0 * az);
      const Eigen::Vector3f p(static_cast<float>(range * std::cos(el) * std::cos(az)),
                              static_cast<float>(range * std::cos(el) * std::sin(az)),
                              static_cast<float>(range * std::sin(el)));
      rings[r].push_back(p);
      scan.push_back(p);
    }
  }
  for (int r = 0; r < kRings; ++r) {
    const auto kept = std::count_if(rings[r].begin(), rings[r].end(),
                                    [](const auto& p) { return point_filter_keeps(p, kN); });
    // Binomial(2000, 1/4): sd 19; 5 sd.
    EXPECT_NEAR(static_cast<double>(kept), kColumns / 4.0, 100.0) << "ring " << r;
  }
  // The kept points of the scan, and of the scan starting elsewhere (another cut) and shuffled.
  const auto kept_set = [&](const std::vector<Eigen::Vector3f>& points) {
    std::set<std::tuple<float, float, float>> s;
    for (const auto& p : points) {
      if (point_filter_keeps(p, kN)) s.insert({p.x(), p.y(), p.z()});
    }
    return s;
  };
  auto other = scan;
  std::rotate(other.begin(), other.begin() + 12345, other.end());
  std::shuffle(other.begin(), other.end(), std::mt19937(2));
  EXPECT_EQ(kept_set(other), kept_set(scan));
  EXPECT_TRUE(point_filter_keeps(scan.front(), 1));
}

}  // namespace
}  // namespace livod::estimator
