#include "estimator/lio/downsample.hpp"

#include <cmath>

#include "core/hash_mix.hpp"
#include "estimator/grid_index.hpp"

namespace livod::estimator {

std::array<std::int64_t, 3> quantise(const Eigen::Vector3d& p, double inv_quantum) {
  return {floor_to_int(p.x() * inv_quantum + 0.5), floor_to_int(p.y() * inv_quantum + 0.5),
          floor_to_int(p.z() * inv_quantum + 0.5)};
}

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

bool VoxelGridDownsampler::choose(const std::vector<Eigen::Vector3d>& points) {
  if (cell_ <= 0.0) return false;
  reserve_slots(points.size());
  if (++generation_ == 0) {  // wrapped: stale stamps could match again
    for (auto& s : slots_) s.generation = 0;
    generation_ = 1;
  }
  cells_.clear();
  cell_of_point_.resize(points.size());
  const std::size_t mask = slots_.size() - 1;
  constexpr double kInvQuantum = 1.0 / kQuantumM;
  // 1. Cells and their centroids, from exact integer sums (independent of the points' order).
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
    const auto q = quantise(p, kInvQuantum);
    for (int a = 0; a < 3; ++a) c.sum[a] += q[a];
    ++c.count;
    cell_of_point_[k] = slot.cell;
  }
  for (Cell& c : cells_) {
    const double n = static_cast<double>(c.count);
    c.centroid =
        Eigen::Vector3d(static_cast<double>(c.sum[0]) / n, static_cast<double>(c.sum[1]) / n,
                        static_cast<double>(c.sum[2]) / n);
  }
  // 2. The measured point nearest to its cell's centroid, in quantised coordinates; of equally
  // near points the one with the smallest quantised coordinates (not the first: order-free).
  for (std::size_t k = 0; k < points.size(); ++k) {
    Cell& c = cells_[cell_of_point_[k]];
    const auto q = quantise(points[k], kInvQuantum);
    const Eigen::Vector3d d(static_cast<double>(q[0]) - c.centroid.x(),
                            static_cast<double>(q[1]) - c.centroid.y(),
                            static_cast<double>(q[2]) - c.centroid.z());
    const double d2 = d.squaredNorm();
    if (d2 < c.best_d2 || (d2 == c.best_d2 && q < c.best_q)) {
      c.best_d2 = d2;
      c.best_q = q;
      c.best = static_cast<std::uint32_t>(k);
    }
  }
  return true;
}

void VoxelGridDownsampler::apply(std::vector<Eigen::Vector3d>& points) {
  if (!choose(points)) return;
  // Cells are in order of first appearance and each keeps a point at or after that index, so the
  // points can be compacted in place.
  for (std::size_t i = 0; i < cells_.size(); ++i) points[i] = points[cells_[i].best];
  points.resize(cells_.size());
}

void VoxelGridDownsampler::select(const std::vector<Eigen::Vector3d>& points,
                                  std::vector<std::uint32_t>& indices) {
  if (!choose(points)) return;
  for (std::size_t i = 0; i < cells_.size(); ++i) indices[i] = indices[cells_[i].best];
  indices.resize(cells_.size());
}

}  // namespace livod::estimator
