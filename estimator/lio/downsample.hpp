#pragma once
// Voxel-grid downsampling of a scan (FAST-LIVO2 filter_size_surf): one point per occupied cell,
// a measured point chosen blind to where the noise put it.
//
// Not the centroid itself (PCL VoxelGrid, FAST-LIVO2): in a cell that holds an edge, a corner, a
// pole or a crown the centroid lies off every surface, and where it lies depends on how the
// viewpoint samples the cell. Driving forward, every such cell is seen first from ahead, then from
// the side, so the phantom points moved consistently with the motion and biased the registration
// against the map (measured against a map built from true poses, street, OS1-64, 0.5 m cells:
// -1.2 mm along the motion and +0.0006 deg of pitch per scan; the 15-minute drive sank 17-20 m).
// A measured point lies on a surface.
//
// Nor the measured point nearest to the centroid (livod up to stop 29): where each point lies in
// its cell depends on where the range noise moved it, so any rule that chooses by position selects
// on the noise. Against a map built from true poses (street, OS1-64, 0.15 m cells) the nearest to
// the centroid tilted every scan's pitch by +22 urad, the nearest by direction by -22 urad, the
// first in scan order by +3.6 urad (and -14 urad of yaw); the 15-minute street drive climbed 14 m.
// The kept point is the one of smallest selection_rank(): a hash of its quantised coordinates,
// uniform over the cell's points and blind to the geometry, so the kept points carry the noise of
// all points (+1.0 urad there; docs/estimator.md, "Long drives", "Which point a scan cell keeps").
// Rules blind to the range noise but not to the place in the cell (the ray nearest to the cell
// centre's direction, or to the members' mean direction) were not: which points lie in a cell is
// itself decided by their noise where a surface crosses it at a slant. The price: no even spread
// and no denoising (the nearest to the centroid tended to keep a point of small noise), which the
// 36 s replays of the sparse streets feel (8-18 % more ATE on the 32-ring ones).
//
// Which point a cell keeps depends on the set of points only, not on their order: the rank is a
// function of the point's coordinates quantised to kQuantumM, and equal ranks are told apart by
// the coordinates, not by the index. The same scan delivered by another container (bag,
// pcap, folder) or cut at another packet then keeps the same points.
//
// The cell table is kept between calls so that steady state does not allocate: an
// open-addressing table of packed cell keys whose slots are stamped with the call's generation,
// so a new call needs no clearing pass.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace livod::estimator {

class VoxelGridDownsampler {
 public:
  // The coordinate quantum of the selection rank (0.1 mm: far below any LiDAR's range noise, so
  // distinct returns have distinct coordinates).
  static constexpr double kQuantumM = 1e-4;

  explicit VoxelGridDownsampler(double cell_size)
      : cell_(cell_size), inv_cell_(cell_size > 0.0 ? 1.0 / cell_size : 0.0) {}

  // Replaces `points` by one point per cell (the one of smallest selection_rank), cells in
  // order of first appearance (so the output is deterministic). cell_size <= 0 leaves the points
  // unchanged.
  void apply(std::vector<Eigen::Vector3d>& points);
  // The same into `out` (in is left as it is).
  void apply(const std::vector<Eigen::Vector3d>& in, std::vector<Eigen::Vector3d>& out);
  // The same selection as indices: `points[k]` is the point of `indices[k]`; on return `indices`
  // holds the indices of the kept points (cells in order of first appearance).
  void select(const std::vector<Eigen::Vector3d>& points, std::vector<std::uint32_t>& indices);

  void set_cell(double cell_size) {
    cell_ = cell_size;
    inv_cell_ = cell_size > 0.0 ? 1.0 / cell_size : 0.0;
  }
  [[nodiscard]] double cell() const { return cell_; }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t generation = 0;  // slot is in use for the current call when equal to gen_
    std::uint32_t cell = 0;        // index into cells_
  };
  struct Cell {
    std::uint64_t best_rank = 0;
    std::uint32_t best = 0;  // index (into the call's points) of the point kept
  };
  void reserve_slots(std::size_t points);
  // Fills best of each cell of `points` into cells_ (cells in order of first appearance); false
  // when the cell size disables downsampling.
  bool choose(const std::vector<Eigen::Vector3d>& points);

  double cell_;
  double inv_cell_;
  std::vector<Slot> slots_;
  std::vector<Cell> cells_;
  std::uint32_t generation_ = 0;
};

// The coordinates of p quantised to `quantum` (rounded to the nearest multiple).
std::array<std::int64_t, 3> quantise(const Eigen::Vector3d& p, double inv_quantum);

// The rank by which a cell chooses its point: a hash of the point's quantised coordinates, the
// same for the same point in any scan and uniform over the points of a cell.
std::uint64_t selection_rank(const std::array<std::int64_t, 3>& q);

}  // namespace livod::estimator
