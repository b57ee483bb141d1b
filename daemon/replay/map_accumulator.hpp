#pragma once
// The exported map (OUTDIR/map.pcd): the registered, downsampled points of every frame through a
// voxel filter that keeps the first point to land in each cell, up to a point budget. Keeping the
// first point (not a running centroid) makes the output independent of later frames and costs one
// hash probe per point; the cell size bounds the density, the budget bounds memory for
// recordings that never revisit a place (a street): once full, points in new cells are counted
// and dropped.
//
// Memory: 12 bytes per kept point (16 with a colour) plus an open-addressing table of 8-byte cell
// keys kept at most half full, grown by doubling: at most 12 + 4 x 8 = 44 bytes per point of the
// budget.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "io/pcd_writer.hpp"

namespace livod::daemon::replay {

class MapAccumulator {
 public:
  // Throws std::invalid_argument for a cell size <= 0 or a zero budget.
  MapAccumulator(double cell_size_m, std::size_t max_points);

  // Adds one world point; returns false when its cell was already taken or the budget is spent.
  bool add(const Eigen::Vector3d& p_world);
  // The same with a colour (0x00RRGGBB; a camera's map). Use one form per accumulator.
  bool add(const Eigen::Vector3d& p_world, std::uint32_t rgb);

  [[nodiscard]] std::size_t size() const { return xyz_.size() / 3; }
  [[nodiscard]] std::uint64_t dropped_full() const { return dropped_full_; }
  // Points beyond the cell grid (+-1,048,575 cells per axis) or not finite: not mapped.
  [[nodiscard]] std::uint64_t dropped_outside() const { return dropped_outside_; }
  // Half the extent of the grid along each axis (m).
  [[nodiscard]] double grid_half_extent_m() const;
  // Heap bytes held (point storage + table capacity).
  [[nodiscard]] std::size_t bytes() const;
  [[nodiscard]] const std::vector<float>& xyz() const { return xyz_; }
  // Colours of the points added with one (empty when none were).
  [[nodiscard]] const std::vector<std::uint32_t>& rgb() const { return rgb_; }

 private:
  void grow();

  double inv_cell_;
  std::size_t max_points_;
  std::vector<float> xyz_;
  std::vector<std::uint32_t> rgb_;
  std::vector<std::uint64_t> table_;  // 0 = empty slot; keys are never 0 (see the .cpp)
  std::uint64_t dropped_full_ = 0;
  std::uint64_t dropped_outside_ = 0;
};

// Writes x y z float32 points as a binary PCD v0.7 file (io/pcd_writer.hpp). Throws livod::Error
// if the file cannot be written.
inline void write_pcd(const std::filesystem::path& path, const std::vector<float>& xyz) {
  io::write_pcd_xyz(path, xyz);
}
// x y z rgb: the colour packed 0x00RRGGBB in a float32 field, as PCL's PointXYZRGB writes it.
// Throws livod::Error if the file cannot be written.
void write_pcd_rgb(const std::filesystem::path& path, const std::vector<float>& xyz,
                   const std::vector<std::uint32_t>& rgb);

}  // namespace livod::daemon::replay
