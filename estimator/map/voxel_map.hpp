#pragma once
// The LiDAR map: a hash of root voxels, each an octree whose nodes hold planes with uncertainty
// (VoxelMap / FAST-LIVO2, fast-livo2-notes.md 1.3), with FAST-LIVO2's defects fixed:
//  - voxel keys are a true floor (no off-by-one at exact negative multiples),
//  - the neighbouring-voxel fallback works in voxel units (FAST-LIVO2 mixes units),
//  - the map is bounded: it slides with the sensor (roots farther than half_extent per axis are
//    dropped) and frozen planes free their points; memory is accounted in stats().

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/hash_mix.hpp"
#include "estimator/map/plane.hpp"
#include "estimator/params.hpp"
#include "estimator/task_runner.hpp"

namespace livod::estimator {

struct VoxelKey {
  std::int64_t x = 0, y = 0, z = 0;
  friend bool operator==(const VoxelKey&, const VoxelKey&) = default;
};

struct VoxelKeyHash {
  std::size_t operator()(const VoxelKey& k) const {
    // Large primes combine the three coordinates, the splitmix64 finaliser spreads the result
    // over every bit (neighbouring lattice keys otherwise share buckets).
    const auto h = hash_mix(
        static_cast<std::uint64_t>(k.x * 73856093LL ^ k.y * 19349669LL ^ k.z * 83492791LL));
    return static_cast<std::size_t>(h);
  }
};

VoxelKey voxel_key(const Eigen::Vector3d& p, double voxel_size);

struct PlaneMatch {
  const MapPlane* plane = nullptr;
  double distance = 0.0;  // signed point-to-plane distance (m)
  double variance = 0.0;  // its variance: plane + point uncertainty (m^2)
};

struct VoxelMapStats {
  std::size_t root_voxels = 0;
  std::size_t nodes = 0;
  std::size_t planes = 0;
  std::size_t frozen_nodes = 0;
  std::size_t stored_points = 0;
  std::size_t bytes = 0;             // nodes + point storage (capacity), an estimate of heap use
  std::uint64_t removed_voxels = 0;  // dropped by sliding or the budget, since construction
  std::uint64_t evicted_voxels = 0;  // of those, dropped by the budget (max_voxels)
  std::size_t retired_voxels = 0;    // dropped but not freed yet (freed over the next scans)
};

class VoxelMap {
 public:
  VoxelMap(const LioParams& lio, const MapParams& map);
  ~VoxelMap();
  VoxelMap(VoxelMap&&) noexcept;
  VoxelMap& operator=(VoxelMap&&) noexcept;

  // Adds world points (with world covariances) and updates the planes they touch, one root voxel
  // per task on `runner` (nullptr: on the caller). The result does not depend on the runner.
  void insert(const std::vector<CovPoint>& points, TaskRunner* runner = nullptr);

  // The most likely plane for a world point, passing the in-plane extent gate (3 radii) and the
  // sigma_num gate on the distance; looks into the neighbouring voxel nearest the point when the
  // point's own voxel has no match. False when nothing matches.
  bool match(const Eigen::Vector3d& p_world, const Eigen::Matrix3d& cov_world,
             PlaneMatch& out) const;

  struct Node;
  // The root voxel a point was last matched in. match() with a hint skips the hash lookup of the
  // point's own voxel while the point stays in that voxel and the map is unchanged, which is the
  // case over the iterations of one update (the lookup is a large part of matching).
  struct Hint {
    VoxelKey key;
    const Node* root = nullptr;
    std::uint64_t generation = 0;  // 0: empty; the map's generation_ starts at 1
  };
  bool match(const PointQuery& query, PlaneMatch& out, Hint& hint) const;
  // False once the map changed after the hint was made (it will be looked up again).
  [[nodiscard]] bool is_current(const Hint& hint) const { return hint.generation == generation_; }

  // Latency hiding for a stream of matches, which is bound by cache misses (the voxel table, then
  // the voxel's node): prefetch_root() asks for the table slot of a point's voxel some points
  // ahead; resolve(), a few points later, looks the voxel up (its slot now cached), keeps it in
  // the hint and asks for the node; match() with that hint then finds both in cache.
  void prefetch_root(const Eigen::Vector3d& p_world) const;
  void resolve(const Eigen::Vector3d& p_world, Hint& hint) const;

  // Drops root voxels farther than half_extent (per axis) from `position` once the sensor has
  // moved slide_threshold since the last slide; then, if the map holds more than max_voxels roots,
  // the ones farthest from `position` until 90 % of the budget is left (with or without sliding).
  // Returns the number of voxels removed.
  std::size_t slide(const Eigen::Vector3d& position);

  // O(1): the map keeps its counts as it changes (insert, slide), so that the pipeline can report
  // them every scan. A full traversal of a street map took 5.5 ms, every tenth frame.
  [[nodiscard]] VoxelMapStats stats() const;
  // The same figures counted by walking every voxel (for tests: it must equal stats()).
  [[nodiscard]] VoxelMapStats count_by_traversal() const;
  [[nodiscard]] bool empty() const;

 private:
  // What a node or a subtree holds (its part of stats()), or a change of it (signed).
  struct Counts {
    std::int64_t nodes = 0;
    std::int64_t planes = 0;
    std::int64_t frozen_nodes = 0;
    std::int64_t stored_points = 0;
    std::int64_t bytes = 0;
    Counts& operator+=(const Counts& o);
    Counts& operator-=(const Counts& o);
  };
  [[nodiscard]] VoxelMapStats make_stats(const Counts& live, const Counts& retired) const;

  LioParams lio_;
  MapParams map_;
  // Root voxels by key: open addressing with linear probing, kept at most half full. A lookup
  // is one probe run in one array; std::unordered_map chased two pointers per lookup, which
  // dominated matching on large (street) maps.
  class RootTable {
   public:
    RootTable();
    ~RootTable();
    RootTable(RootTable&&) noexcept;
    RootTable& operator=(RootTable&&) noexcept;
    [[nodiscard]] Node* find(const VoxelKey& key) const;
    void prefetch(const VoxelKey& key) const;
    // The entry of `key`, created empty (nullptr) when absent; the caller fills it.
    std::unique_ptr<Node>& operator[](const VoxelKey& key);
    // Moves the roots whose key satisfies `remove` to `removed`; returns how many.
    std::size_t erase_if(const std::function<bool(const VoxelKey&)>& remove,
                         std::vector<std::unique_ptr<Node>>& removed);
    void for_each(const std::function<void(const Node&)>& visit) const;
    void for_each_key(const std::function<void(const VoxelKey&)>& visit) const;
    [[nodiscard]] std::size_t size() const { return size_; }
    [[nodiscard]] std::size_t bytes() const;

   private:
    struct Entry {
      VoxelKey key;
      std::unique_ptr<Node> node;  // nullptr: free slot
    };
    void rehash(std::size_t slots);
    std::vector<Entry> entries_;
    std::size_t size_ = 0;
  };
  RootTable roots_;
  Eigen::Vector3d last_slide_position_ = Eigen::Vector3d::Zero();
  bool slid_once_ = false;
  std::uint64_t removed_ = 0;
  std::uint64_t evicted_ = 0;
  std::size_t evict_over_budget(const VoxelKey& centre);
  // Voxels dropped by slide(), freed at least kRetiredPerInsert per insert() and at least an
  // eighth of the backlog, so that a slide's frees spread over the scans until the next one and
  // the backlog stays bounded (at most ~8 scans' drops) when voxels are dropped faster.
  static constexpr std::size_t kRetiredPerInsert = 512;
  static constexpr std::size_t kRetiredBacklogFraction = 8;
  std::vector<std::unique_ptr<Node>> retired_;
  // Moves the roots of retired_ from index `first` on from the live counts to the retired ones.
  void account_retired(std::size_t first);
  Counts live_counts_;            // the roots in roots_
  Counts retired_counts_;         // the roots in retired_
  std::uint64_t generation_ = 1;  // bumped by every change of the map (invalidates hints)
  // insert()'s work arrays, kept to avoid allocating per scan.
  static constexpr std::uint32_t kNoBatch = 0xFFFFFFFFU;
  std::vector<Node*> batch_roots_;
  std::vector<VoxelKey> point_keys_;
  std::vector<std::uint32_t> point_batch_;
  std::vector<std::uint32_t> batch_offsets_;
  std::vector<std::uint32_t> batch_cursor_;
  std::vector<std::uint32_t> batch_order_;
  std::vector<Counts> batch_change_;  // what each touched root's insert changed
};

}  // namespace livod::estimator
