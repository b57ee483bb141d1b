#include "estimator/lio/downsample.hpp"

#include <cmath>
#include <tuple>

#include "core/hash_mix.hpp"
#include "estimator/grid_index.hpp"

namespace livod::estimator {

std::array<std::int64_t, 3> quantise(const Eigen::Vector3d& p, double inv_quantum) {
  return {floor_to_int(p.x() * inv_quantum + 0.5), floor_to_int(p.y() * inv_quantum + 0.5),
          floor_to_int(p.z() * inv_quantum + 0.5)};
}

namespace {

bool lexicographically_less(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z());
}

}  // namespace

std::uint64_t selection_rank(const std::array<std::int64_t, 3>& q) {
  // Chained splitmix64 over the three coordinates, salted so that it is independent of
  // point_filter_keeps (which hashes packed millimetre coordinates with the same finaliser).
  constexpr std::uint64_t kSalt = 0x6a09e667f3bcc909ULL;
  std::uint64_t h = hash_mix(static_cast<std::uint64_t>(q[0]) ^ kSalt);
  h = hash_mix(h ^ static_cast<std::uint64_t>(q[1]));
  return hash_mix(h ^ static_cast<std::uint64_t>(q[2]));
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
  const std::size_t mask = slots_.size() - 1;
  constexpr double kInvQuantum = 1.0 / kQuantumM;
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
    const std::uint64_t rank = selection_rank(quantise(p, kInvQuantum));
    const auto index = static_cast<std::uint32_t>(k);
    if (slot.generation != generation_) {  // a new cell: its first point is its best so far
      slot = Slot{key, generation_, static_cast<std::uint32_t>(cells_.size())};
      cells_.push_back(Cell{rank, index});
      continue;
    }
    // The point of smallest rank; of equal ranks (points within kQuantumM of each other, or a
    // 64-bit collision) the one with the smallest coordinates (not the first: order-free).
    Cell& c = cells_[slot.cell];
    if (rank < c.best_rank || (rank == c.best_rank && lexicographically_less(p, points[c.best]))) {
      c.best_rank = rank;
      c.best = index;
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
