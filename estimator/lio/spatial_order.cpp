#include "estimator/lio/spatial_order.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "estimator/grid_index.hpp"

namespace livod::estimator {
namespace {

constexpr std::int64_t kBias = std::int64_t{1} << 20;
constexpr std::int64_t kMax = (std::int64_t{1} << 21) - 1;

// Spreads the low 21 bits of v so that two zero bits follow each one.
std::uint64_t spread3(std::uint64_t v) {
  v &= 0x1FFFFFULL;
  v = (v | (v << 32)) & 0x1F00000000FFFFULL;
  v = (v | (v << 16)) & 0x1F0000FF0000FFULL;
  v = (v | (v << 8)) & 0x100F00F00F00F00FULL;
  v = (v | (v << 4)) & 0x10C30C30C30C30C3ULL;
  v = (v | (v << 2)) & 0x1249249249249249ULL;
  return v;
}

std::uint64_t cell_coordinate(double x, double inv_cell) {
  const double scaled = x * inv_cell;
  if (!(std::abs(scaled) < static_cast<double>(kBias))) {  // far away (or NaN): clamp
    return scaled > 0.0 ? static_cast<std::uint64_t>(kMax) : 0;
  }
  return static_cast<std::uint64_t>(floor_to_int(scaled) + kBias);
}

}  // namespace

std::uint64_t morton_code(const Eigen::Vector3d& p, double inv_cell) {
  return spread3(cell_coordinate(p.x(), inv_cell)) |
         (spread3(cell_coordinate(p.y(), inv_cell)) << 1) |
         (spread3(cell_coordinate(p.z(), inv_cell)) << 2);
}

void SpatialOrder::apply(std::vector<Eigen::Vector3d>& points, double cell_m) {
  if (points.size() < 2 || !(cell_m > 0.0)) return;
  const double inv_cell = 1.0 / cell_m;
  const std::size_t n = points.size();
  keys_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    // 30 bits of the code (10 per axis) above the index: unique keys, so the order is total.
    const std::uint64_t code = morton_code(points[i], inv_cell) & 0x3FFFFFFFULL;
    keys_[i] = (code << 32) | static_cast<std::uint64_t>(i);
  }
  // LSD radix sort on the code, 10 bits a pass (stable, so each pass keeps the previous order).
  swap_.resize(n);
  std::array<std::uint32_t, 1024> counts{};
  for (int shift = 32; shift < 62; shift += 10) {
    counts.fill(0);
    for (const std::uint64_t k : keys_) ++counts[(k >> shift) & 1023U];
    std::uint32_t sum = 0;
    for (auto& c : counts) {
      const std::uint32_t here = c;
      c = sum;
      sum += here;
    }
    for (const std::uint64_t k : keys_) swap_[counts[(k >> shift) & 1023U]++] = k;
    keys_.swap(swap_);
  }
  scratch_.resize(n);
  for (std::size_t i = 0; i < n; ++i) scratch_[i] = points[keys_[i] & 0xFFFFFFFFULL];
  points.swap(scratch_);
}

}  // namespace livod::estimator
