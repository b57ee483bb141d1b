// Voxel-grid downsampling keeps one measured point per cell (the one nearest to the cell's
// centroid), and the point budget adapts the cell to the points a scan brings.

#include "estimator/lio/downsample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>

#include "estimator/lio/point_budget.hpp"

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
// one side (nearest to the cell centre, for one, pulls the points toward the cell's middle).
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
  // Each kept point is closer to its cell's centroid than its neighbours: its scatter is below the
  // noise; the mean is zero within a few standard errors of it.
  EXPECT_LT(std::abs(sum / static_cast<double>(n)), 4.0 * 0.02 / std::sqrt(static_cast<double>(n)));
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

}  // namespace
}  // namespace livod::estimator
