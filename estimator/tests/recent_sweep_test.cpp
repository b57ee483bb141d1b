#include "estimator/vio/recent_sweep.hpp"

#include <gtest/gtest.h>

namespace livod::estimator::vio {
namespace {

constexpr std::int64_t kMs = 1'000'000;
const Nanoseconds kPeriod(100 * kMs);  // a 10 Hz LiDAR

MappedTime at_ms(std::int64_t ms) {
  return MappedTime(ms * kMs);
}

// `n` points tagged by x = tag + i.
std::vector<CovPoint> points_tagged(double tag, int n) {
  std::vector<CovPoint> points(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) points[static_cast<std::size_t>(i)].p.x() = tag + i;
  return points;
}

std::vector<double> tags(const std::vector<CovPoint>& points) {
  std::vector<double> out;
  for (const auto& p : points) out.push_back(p.p.x());
  return out;
}

TEST(RecentSweep, AWholeScanPassesThroughUncopied) {
  RecentSweep sweep;
  const auto a = points_tagged(0, 3);
  const std::vector<Eigen::Vector3d> normals(3, Eigen::Vector3d::UnitZ());
  for (std::int64_t t = 100; t <= 500; t += 100) {
    const auto view = sweep.add(at_ms(t - 100), at_ms(t), kPeriod, a, normals);
    EXPECT_EQ(view.points, &a);
    EXPECT_EQ(view.normals, &normals);
  }
  EXPECT_EQ(sweep.stored_points(), 0U);
}

// A 20 Hz camera: each group holds half a sweep, the view the last two halves.
TEST(RecentSweep, HalfScansJoinTheHalfBefore) {
  RecentSweep sweep;
  const auto a = points_tagged(0, 2);
  const auto b = points_tagged(10, 3);
  const auto c = points_tagged(20, 1);
  const std::vector<Eigen::Vector3d> a_normals(2, Eigen::Vector3d::UnitZ());
  const std::vector<Eigen::Vector3d> none;  // b: no plane matched

  auto view = sweep.add(at_ms(400), at_ms(450), kPeriod, a, a_normals);
  EXPECT_EQ(view.points, &a);  // nothing before it
  view = sweep.add(at_ms(450), at_ms(500), kPeriod, b, none);
  EXPECT_EQ(tags(*view.points), (std::vector<double>{0, 1, 10, 11, 12}));
  ASSERT_EQ(view.normals->size(), 5U);
  EXPECT_EQ((*view.normals)[1], Eigen::Vector3d::UnitZ());
  EXPECT_TRUE((*view.normals)[2].isZero());  // b's points have no normal
  view = sweep.add(at_ms(500), at_ms(550), kPeriod, c, std::vector<Eigen::Vector3d>(1));
  EXPECT_EQ(tags(*view.points), (std::vector<double>{10, 11, 12, 20}));  // a is 150 ms old
  EXPECT_EQ(view.normals->size(), 4U);
  EXPECT_EQ(sweep.stored_points(), 4U);  // b and c: the next group may join them

  // A whole scan (the camera stopped) is a sweep of its own and ends the parts.
  const auto d = points_tagged(30, 2);
  view = sweep.add(at_ms(550), at_ms(650), kPeriod, d, none);
  EXPECT_EQ(view.points, &d);
  EXPECT_EQ(sweep.stored_points(), 0U);
}

// Image times jitter: a part that began up to a tenth of a period more than a period before the
// update still joins it.
TEST(RecentSweep, ATenthOfAPeriodOfJitter) {
  RecentSweep sweep;
  const auto a = points_tagged(0, 1);
  const auto b = points_tagged(10, 1);
  const std::vector<Eigen::Vector3d> none;
  sweep.add(at_ms(0), at_ms(52), kPeriod, a, none);
  auto view = sweep.add(at_ms(52), at_ms(109), kPeriod, b, none);
  EXPECT_EQ(tags(*view.points), (std::vector<double>{0, 10}));

  RecentSweep later;
  later.add(at_ms(0), at_ms(52), kPeriod, a, none);
  view = later.add(at_ms(52), at_ms(111), kPeriod, b, none);
  EXPECT_EQ(view.points, &b);
}

}  // namespace
}  // namespace livod::estimator::vio
