#pragma once
// Voxel-grid downsampling of a scan (FAST-LIVO2 filter_size_surf, PCL VoxelGrid semantics:
// one centroid per occupied cell). The cell table is kept between calls so that steady state
// does not allocate: an open-addressing table of packed cell keys whose slots are stamped with
// the call's generation, so a new call needs no clearing pass.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace livod::estimator {

class VoxelGridDownsampler {
 public:
  explicit VoxelGridDownsampler(double cell_size)
      : cell_(cell_size), inv_cell_(cell_size > 0.0 ? 1.0 / cell_size : 0.0) {}

  // Replaces `points` by the centroids of their cells, in order of first appearance (so the
  // output is deterministic). cell_size <= 0 leaves the points unchanged.
  void apply(std::vector<Eigen::Vector3d>& points);

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t generation = 0;  // slot is in use for the current call when equal to gen_
    std::uint32_t cell = 0;        // index into cells_
  };
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
  };
  void reserve_slots(std::size_t points);

  double cell_;
  double inv_cell_;
  std::vector<Slot> slots_;
  std::vector<Cell> cells_;
  std::uint32_t generation_ = 0;
};

}  // namespace livod::estimator
