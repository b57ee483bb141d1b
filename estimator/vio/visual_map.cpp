#include "estimator/vio/visual_map.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace livod::estimator::vio {

VisualMap::VisualMap(double voxel_size, const MapParams& map, std::size_t max_points)
    : voxel_size_(voxel_size), map_(map), max_points_(std::max<std::size_t>(1, max_points)) {}

std::uint32_t VisualMap::add(VisualPoint point) {
  point.alive = true;
  const VoxelKey key = voxel_key(point.p_world, voxel_size_);
  std::uint32_t id = 0;
  if (!free_.empty()) {
    id = free_.back();
    free_.pop_back();
    points_[id] = std::move(point);
  } else {
    id = static_cast<std::uint32_t>(points_.size());
    points_.push_back(std::move(point));
  }
  voxels_[key].ids.push_back(id);
  ++created_;
  return id;
}

void VisualMap::remove(std::uint32_t id) {
  VisualPoint& p = points_[id];
  if (!p.alive) return;
  const VoxelKey key = voxel_key(p.p_world, voxel_size_);
  if (const auto it = voxels_.find(key); it != voxels_.end()) {
    auto& ids = it->second.ids;
    ids.erase(std::remove(ids.begin(), ids.end(), id), ids.end());
    if (ids.empty()) voxels_.erase(it);
  }
  // Release the patches' memory now (a moved-from vector may keep its capacity).
  std::vector<PatchObservation>().swap(p.observations);
  p.alive = false;
  free_.push_back(id);
}

void VisualMap::gather(const std::vector<VoxelKey>& keys, std::vector<std::uint32_t>& ids) {
  ids.clear();
  ++visit_;
  // The keys looked up lately, direct-mapped by hash: a key met again (the scan's points revisit
  // a voxel many times, not only in runs) needs no table lookup, its voxel was gathered (or it has
  // none). The same ids in the same order as looking every key up.
  constexpr std::size_t kRecent = 64;
  std::array<VoxelKey, kRecent> recent{};
  std::array<bool, kRecent> have{};
  const VoxelKeyHash hash;
  for (const auto& key : keys) {
    const std::size_t slot = hash(key) % kRecent;
    if (have[slot] && recent[slot] == key) continue;
    recent[slot] = key;
    have[slot] = true;
    const auto it = voxels_.find(key);
    if (it == voxels_.end() || it->second.visit == visit_) continue;
    it->second.visit = visit_;
    ids.insert(ids.end(), it->second.ids.begin(), it->second.ids.end());
  }
}

std::size_t VisualMap::slide(const Eigen::Vector3d& position) {
  if (!map_.sliding) return 0;
  if (slid_once_ && (position - last_slide_position_).norm() < map_.slide_threshold_m) return 0;
  slid_once_ = true;
  last_slide_position_ = position;
  const VoxelKey c = voxel_key(position, voxel_size_);
  const auto reach = static_cast<std::int64_t>(std::ceil(map_.half_extent_m / voxel_size_));
  std::vector<std::uint32_t> doomed;
  for (const auto& [key, voxel] : voxels_) {
    if (std::abs(key.x - c.x) > reach || std::abs(key.y - c.y) > reach ||
        std::abs(key.z - c.z) > reach) {
      doomed.insert(doomed.end(), voxel.ids.begin(), voxel.ids.end());
    }
  }
  // Ascending ids: the order of removal (and of the free list) does not depend on the hash.
  std::sort(doomed.begin(), doomed.end());
  for (const auto id : doomed) remove(id);
  removed_sliding_ += doomed.size();
  return doomed.size();
}

std::size_t VisualMap::enforce_budget() {
  if (size() <= max_points_) return 0;
  const std::size_t target = max_points_ - max_points_ / 10;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> by_age;
  by_age.reserve(size());
  for (std::uint32_t id = 0; id < points_.size(); ++id) {
    if (points_[id].alive) by_age.emplace_back(points_[id].last_seen, id);
  }
  const std::size_t n = by_age.size() - target;
  std::nth_element(by_age.begin(), by_age.begin() + static_cast<std::ptrdiff_t>(n), by_age.end());
  std::sort(by_age.begin(), by_age.begin() + static_cast<std::ptrdiff_t>(n));
  for (std::size_t i = 0; i < n; ++i) remove(by_age[i].second);
  removed_budget_ += n;
  return n;
}

VisualMapStats VisualMap::stats() const {
  VisualMapStats s;
  s.points = size();
  s.voxels = voxels_.size();
  s.created = created_;
  s.removed_sliding = removed_sliding_;
  s.removed_budget = removed_budget_;
  s.bytes = points_.capacity() * sizeof(VisualPoint) + free_.capacity() * sizeof(std::uint32_t);
  for (const auto& p : points_) {
    s.observations += p.observations.size();
    s.bytes += p.observations.capacity() * sizeof(PatchObservation);
    for (const auto& o : p.observations) s.bytes += o.blocks.capacity();
  }
  // unordered_map: a node per voxel (key, vector, visit, next pointer, cached hash) + buckets.
  s.bytes += voxels_.bucket_count() * sizeof(void*);
  for (const auto& [key, voxel] : voxels_) {
    s.bytes += sizeof(VoxelKey) + sizeof(Voxel) + 2 * sizeof(void*) +
               voxel.ids.capacity() * sizeof(std::uint32_t);
  }
  return s;
}

}  // namespace livod::estimator::vio
