#include "estimator/lio/downsample.hpp"

#include <cmath>

#include "core/hash_mix.hpp"
#include "estimator/grid_index.hpp"

namespace livod::estimator {

void VoxelGridDownsampler::reserve_slots(std::size_t points) {
  // At most half full even if every point has its own cell.
  std::size_t n = slots_.empty() ? 1024 : slots_.size();
  while (n < 2 * points) n *= 2;
  if (n != slots_.size()) {
    slots_.assign(n, Slot{});
    generation_ = 0;
  }
}

void VoxelGridDownsampler::apply(const std::vector<Eigen::Vector3d>& in,
                                 std::vector<Eigen::Vector3d>& out) {
  out = in;
  apply(out);
}

void VoxelGridDownsampler::apply(std::vector<Eigen::Vector3d>& points) {
  if (cell_ <= 0.0) return;
  reserve_slots(points.size());
  if (++generation_ == 0) {  // wrapped: stale stamps could match again
    for (auto& s : slots_) s.generation = 0;
    generation_ = 1;
  }
  cells_.clear();
  cell_of_point_.resize(points.size());
  const std::size_t mask = slots_.size() - 1;
  // 1. Cells and their centroids.
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d& p = points[k];
    // 21 bits per axis (+-1M cells, +-104 km at 0.1 m) packed into one key.
    const auto ix = floor_to_int(p.x() * inv_cell_) & 0x1FFFFF;
    const auto iy = floor_to_int(p.y() * inv_cell_) & 0x1FFFFF;
    const auto iz = floor_to_int(p.z() * inv_cell_) & 0x1FFFFF;
    const std::uint64_t key = (static_cast<std::uint64_t>(ix) << 42) |
                              (static_cast<std::uint64_t>(iy) << 21) |
                              static_cast<std::uint64_t>(iz);
    std::size_t i = hash_mix(key) & mask;
    while (slots_[i].generation == generation_ && slots_[i].key != key) i = (i + 1) & mask;
    Slot& slot = slots_[i];
    if (slot.generation != generation_) {
      slot = Slot{key, generation_, static_cast<std::uint32_t>(cells_.size())};
      cells_.push_back(Cell{});
    }
    Cell& c = cells_[slot.cell];
    c.sum += p;
    ++c.count;
    cell_of_point_[k] = slot.cell;
  }
  for (Cell& c : cells_) c.centroid = c.sum / static_cast<double>(c.count);
  // 2. The measured point nearest to its cell's centroid (the first of equals).
  for (std::size_t k = 0; k < points.size(); ++k) {
    Cell& c = cells_[cell_of_point_[k]];
    const double d2 = (points[k] - c.centroid).squaredNorm();
    if (d2 < c.best_d2) {
      c.best_d2 = d2;
      c.best = static_cast<std::uint32_t>(k);
    }
  }
  // Cells are in order of first appearance and each keeps a point at or after that index, so the
  // points can be compacted in place.
  for (std::size_t i = 0; i < cells_.size(); ++i) points[i] = points[cells_[i].best];
  points.resize(cells_.size());
}

}  // namespace livod::estimator
