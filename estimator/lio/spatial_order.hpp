#pragma once
// Reorders a scan's points so that points of the same map voxel follow each other (Morton / Z
// order of their cells). Matching and map insertion are bound by memory latency - one cache miss
// on the voxel table and one on the voxel's node per point in scan order - and points of one voxel
// in a row find both in cache. The order changes nothing but the order of floating-point sums;
// it is a pure function of the points, so results stay deterministic.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace livod::estimator {

// 63-bit Morton code of the cell of p (21 bits per axis, cells within +-2^20 of the origin; farther
// coordinates are clamped, which only affects the order).
std::uint64_t morton_code(const Eigen::Vector3d& p, double inv_cell);

class SpatialOrder {
 public:
  // Sorts `points` by the Morton code of their cell of edge `cell_m` (ties keep their order). The
  // order uses the low 10 bits of each cell coordinate (a 1024-cell block), which groups what is
  // near within a block; a radix sort keeps this well under a millisecond per scan.
  void apply(std::vector<Eigen::Vector3d>& points, double cell_m);

 private:
  std::vector<std::uint64_t> keys_;  // Morton code (upper 32 bits) | point index
  std::vector<std::uint64_t> swap_;
  std::vector<Eigen::Vector3d> scratch_;
};

}  // namespace livod::estimator
