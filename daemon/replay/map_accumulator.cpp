#include "daemon/replay/map_accumulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "core/hash_mix.hpp"
#include "io/output_file.hpp"

namespace livod::daemon::replay {
namespace {

constexpr std::size_t kInitialSlots = 1 << 12;
// Cell coordinates are packed into 21 bits each (+-1,048,575 cells: +-210 km at 0.2 m); points
// beyond are not mapped. The bias keeps every packed key non-zero, so 0 marks an empty slot.
constexpr std::int64_t kCoordBias = 1 << 20;
constexpr std::int64_t kCoordLimit = (1 << 21) - 1;

}  // namespace

MapAccumulator::MapAccumulator(double cell_size_m, std::size_t max_points)
    : inv_cell_(1.0 / cell_size_m), max_points_(max_points) {
  if (!(cell_size_m > 0.0) || max_points == 0) {
    throw std::invalid_argument("map cell size must be > 0 and the point budget > 0");
  }
  table_.assign(kInitialSlots, 0);
}

bool MapAccumulator::add(const Eigen::Vector3d& p) {
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double c = std::floor(p[axis] * inv_cell_);
    const auto biased = std::abs(c) < static_cast<double>(kCoordBias)  // false for NaN
                            ? static_cast<std::int64_t>(c) + kCoordBias
                            : std::int64_t{0};
    if (biased <= 0 || biased > kCoordLimit) {
      ++dropped_outside_;
      return false;
    }
    key = (key << 21) | static_cast<std::uint64_t>(biased);
  }
  const std::size_t mask = table_.size() - 1;
  std::size_t slot = hash_mix(key) & mask;
  while (table_[slot] != 0) {
    if (table_[slot] == key) return false;
    slot = (slot + 1) & mask;
  }
  if (size() >= max_points_) {
    ++dropped_full_;
    return false;
  }
  table_[slot] = key;
  xyz_.push_back(static_cast<float>(p.x()));
  xyz_.push_back(static_cast<float>(p.y()));
  xyz_.push_back(static_cast<float>(p.z()));
  if (2 * size() > table_.size()) grow();
  return true;
}

bool MapAccumulator::add(const Eigen::Vector3d& p_world, std::uint32_t rgb) {
  if (!add(p_world)) return false;
  rgb_.push_back(rgb);
  return true;
}

double MapAccumulator::grid_half_extent_m() const {
  return static_cast<double>(kCoordBias - 1) / inv_cell_;
}

void MapAccumulator::grow() {
  std::vector<std::uint64_t> old;
  old.swap(table_);
  table_.assign(old.size() * 2, 0);
  const std::size_t mask = table_.size() - 1;
  for (const std::uint64_t key : old) {
    if (key == 0) continue;
    std::size_t slot = hash_mix(key) & mask;
    while (table_[slot] != 0) slot = (slot + 1) & mask;
    table_[slot] = key;
  }
}

std::size_t MapAccumulator::bytes() const {
  return xyz_.capacity() * sizeof(float) + rgb_.capacity() * sizeof(std::uint32_t) +
         table_.capacity() * sizeof(std::uint64_t);
}

void write_pcd_rgb(const std::filesystem::path& path, const std::vector<float>& xyz,
                   const std::vector<std::uint32_t>& rgb) {
  const std::size_t n = std::min(xyz.size() / 3, rgb.size());
  io::OutputFile file(path, true);
  std::ostream& out = file.stream();
  out << "# .PCD v0.7 - Point Cloud Data file format\n"
      << "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
      << "WIDTH " << n << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << n << "\nDATA binary\n";
  std::vector<char> buffer(n * 16);
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(&buffer[i * 16], &xyz[3 * i], 12);
    std::memcpy(&buffer[i * 16 + 12], &rgb[i], 4);
  }
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  file.commit();
}

}  // namespace livod::daemon::replay
