// The maps livod writes are read by PCL (pcl_viewer, pcl::io::loadPCDFile): a map saved while
// running (runtime/map_saver.hpp) and the map.pcd written at stop (io/pcd_writer.hpp) load with
// PCL's own reader, every point equal to the map's, bit for bit. The only test linked with PCL.

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <random>

#include "daemon/replay/map_accumulator.hpp"
#include "daemon/runtime/map_saver.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::runtime {
namespace {

replay::MapAccumulator random_map(std::size_t n) {
  replay::MapAccumulator map(0.01, n);
  map.reserve_budget();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-200.0, 200.0);
  while (map.size() < n) map.add(Eigen::Vector3d(u(rng), u(rng), 0.1 * u(rng)));
  return map;
}

void expect_same_points(const std::filesystem::path& path, const replay::MapAccumulator& map) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile<pcl::PointXYZ>(path.string(), cloud), 0) << path;
  ASSERT_EQ(cloud.size(), map.size());
  EXPECT_EQ(cloud.height, 1U);
  EXPECT_EQ(cloud.width, map.size());
  const auto& xyz = map.xyz();
  std::size_t different = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (p.x != xyz[3 * i] || p.y != xyz[3 * i + 1] || p.z != xyz[3 * i + 2]) ++different;
  }
  EXPECT_EQ(different, 0U) << "points that differ in " << path;
}

TEST(MapSavePcl, SavedMapLoadsWithPclWithEveryPoint) {
  const auto dir = test::temp_dir("mapsave-pcl");
  const auto map = random_map(200'000);
  MapSaverOptions o;
  o.directory = dir;
  MapSaver saver(o, {});
  ASSERT_TRUE(saver.start(map.xyz().data(), map.size(), 1'795'673'465'000'000'000));
  const auto outcome = saver.wait();
  ASSERT_TRUE(outcome && outcome->ok) << (outcome ? outcome->error : "no outcome");
  EXPECT_EQ(outcome->path.filename(), "map-20261126T061105Z-0001.pcd");
  expect_same_points(outcome->path, map);

  // The map written at stop (outputs.map_pcd) by the same PCD writer family.
  replay::write_pcd(dir / "stop.pcd", map.xyz());
  expect_same_points(dir / "stop.pcd", map);
}

}  // namespace
}  // namespace livod::daemon::runtime
