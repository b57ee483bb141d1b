#include "estimator/lio/downsample.hpp"

#include <cmath>

namespace livod::estimator {

void VoxelGridDownsampler::apply(std::vector<Eigen::Vector3d>& points) {
  if (cell_ <= 0.0) return;
  cells_.clear();
  order_.clear();
  for (const auto& p : points) {
    // 21 bits per axis (+-1M cells, +-104 km at 0.1 m) packed into one key.
    const auto ix = static_cast<std::int64_t>(std::floor(p.x() / cell_)) & 0x1FFFFF;
    const auto iy = static_cast<std::int64_t>(std::floor(p.y() / cell_)) & 0x1FFFFF;
    const auto iz = static_cast<std::int64_t>(std::floor(p.z() / cell_)) & 0x1FFFFF;
    const std::uint64_t key = (static_cast<std::uint64_t>(ix) << 42) |
                              (static_cast<std::uint64_t>(iy) << 21) |
                              static_cast<std::uint64_t>(iz);
    auto [it, inserted] = cells_.try_emplace(key);
    if (inserted) {
      it->second.order = static_cast<std::uint32_t>(order_.size());
      order_.push_back(key);
    }
    it->second.sum += p;
    ++it->second.count;
  }
  points.resize(order_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) {
    const Cell& c = cells_.at(order_[i]);
    points[i] = c.sum / static_cast<double>(c.count);
  }
}

}  // namespace livod::estimator
