#pragma once
// Voxel-grid downsampling of a scan (FAST-LIVO2 filter_size_surf, PCL VoxelGrid semantics:
// one centroid per occupied cell). The cell table is kept between calls so that steady state
// does not reallocate.

#include <Eigen/Core>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace livod::estimator {

class VoxelGridDownsampler {
 public:
  explicit VoxelGridDownsampler(double cell_size) : cell_(cell_size) {}

  // Replaces `points` by the centroids of their cells, in order of first appearance (so the
  // output is deterministic). cell_size <= 0 leaves the points unchanged.
  void apply(std::vector<Eigen::Vector3d>& points);

 private:
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    std::uint32_t order = 0;
  };
  double cell_;
  std::unordered_map<std::uint64_t, Cell> cells_;
  std::vector<std::uint64_t> order_;
};

}  // namespace livod::estimator
