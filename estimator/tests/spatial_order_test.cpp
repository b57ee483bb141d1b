#include "estimator/lio/spatial_order.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace livod::estimator {
namespace {

TEST(SpatialOrder, IsAPermutationSortedByCellCode) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-60.0, 60.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 5000; ++i) points.emplace_back(u(rng), u(rng), 0.1 * u(rng));
  // Exact duplicates must survive as duplicates.
  points.push_back(points[17]);
  std::vector<Eigen::Vector3d> sorted = points;
  SpatialOrder order;
  order.apply(sorted, 0.5);
  ASSERT_EQ(sorted.size(), points.size());
  auto lexicographic = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  auto a = points;
  auto b = sorted;
  std::sort(a.begin(), a.end(), lexicographic);
  std::sort(b.begin(), b.end(), lexicographic);
  EXPECT_TRUE(a == b) << "not a permutation";
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    ASSERT_LE(morton_code(sorted[i - 1], 2.0) & 0x3FFFFFFFULL,
              morton_code(sorted[i], 2.0) & 0x3FFFFFFFULL)
        << i;
  }
  // Points of one cell end up next to each other: far fewer cell changes than in random order.
  auto cell_changes = [](const std::vector<Eigen::Vector3d>& v) {
    int changes = 0;
    for (std::size_t i = 1; i < v.size(); ++i) {
      changes += morton_code(v[i - 1], 2.0) != morton_code(v[i], 2.0) ? 1 : 0;
    }
    return changes;
  };
  std::vector<Eigen::Vector3d> dense;
  for (int i = 0; i < 5000; ++i) dense.emplace_back(0.05 * u(rng), 0.05 * u(rng), 0.0);
  const int before = cell_changes(dense);
  order.apply(dense, 0.5);
  EXPECT_LT(cell_changes(dense) * 20, before);
}

TEST(SpatialOrder, MortonCodeInterleavesTheAxes) {
  // Cell (1, 0, 0) -> bit 0, (0, 1, 0) -> bit 1, (0, 0, 1) -> bit 2, relative to the biased origin.
  const std::uint64_t origin = morton_code(Eigen::Vector3d(0.1, 0.1, 0.1), 1.0);
  EXPECT_EQ(morton_code(Eigen::Vector3d(1.1, 0.1, 0.1), 1.0) ^ origin, 1U);
  EXPECT_EQ(morton_code(Eigen::Vector3d(0.1, 1.1, 0.1), 1.0) ^ origin, 2U);
  EXPECT_EQ(morton_code(Eigen::Vector3d(0.1, 0.1, 1.1), 1.0) ^ origin, 4U);
  // Negative coordinates floor, they do not truncate.
  EXPECT_NE(morton_code(Eigen::Vector3d(-0.1, 0.1, 0.1), 1.0), origin);
}

}  // namespace
}  // namespace livod::estimator
