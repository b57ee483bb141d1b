#include "estimator/map/voxel_map.hpp"

#include "estimator/grid_index.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace livod::estimator {

VoxelKey voxel_key(const Eigen::Vector3d& p, double voxel_size) {
  // floor(p / s) exactly as the division gives it: a multiplication by 1/s can round a point
  // lying on a voxel face into the neighbour.
  return VoxelKey{floor_to_int(p.x() / voxel_size), floor_to_int(p.y() / voxel_size),
                  floor_to_int(p.z() / voxel_size)};
}

struct VoxelMap::Node {
  // What matching reads first (split, children, the plane's gate fields) is kept together.
  bool split = false;
  bool initialized = false;
  bool frozen = false;
  int layer = 0;
  int new_points = 0;  // since the last fit
  MapPlane plane;
  std::array<std::unique_ptr<Node>, 8> children;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // of the node's cube
  double half = 0.0;                                 // half edge of the cube
  std::vector<CovPoint> points;                      // kept until the node freezes
  // A plane past LioParams::max_cov_points: the moments of all its points instead of the points,
  // and the plane they were fitted to last (its covariance).
  struct Moments {
    PointMoments moments;
    MapPlane reference;
    double reference_points = 0.0;
  };
  std::unique_ptr<Moments> beyond;
  std::uint32_t batch = kNoBatch;  // roots: index in the insert() under way

  int octant(const Eigen::Vector3d& p) const {
    return (p.x() >= center.x() ? 1 : 0) | (p.y() >= center.y() ? 2 : 0) |
           (p.z() >= center.z() ? 4 : 0);
  }

  // This node's own part of the map's counts (accumulate() sums it over a subtree).
  Counts own() const {
    Counts c;
    c.nodes = 1;
    c.planes = plane.is_plane && !split ? 1 : 0;
    c.frozen_nodes = frozen ? 1 : 0;
    c.stored_points = static_cast<std::int64_t>(points.size());
    c.bytes = static_cast<std::int64_t>(sizeof(Node) + points.capacity() * sizeof(CovPoint) +
                                        (beyond ? sizeof(Moments) : 0));
    return c;
  }

  // Adds what a node's own part changed between construction and destruction to `change`: every
  // change of a node happens inside one, so the map's counts follow without walking the map.
  class OwnChange {
   public:
    OwnChange(const Node& node, Counts& change) : node_(node), change_(change) {
      change_ -= node_.own();
    }
    ~OwnChange() { change_ += node_.own(); }
    OwnChange(const OwnChange&) = delete;
    OwnChange& operator=(const OwnChange&) = delete;

   private:
    const Node& node_;
    Counts& change_;
  };

  Node* child(int o, Counts& change) {
    if (!children[static_cast<std::size_t>(o)]) {
      auto c = std::make_unique<Node>();
      c->layer = layer + 1;
      c->half = half / 2;
      c->center =
          center + Eigen::Vector3d((o & 1) ? c->half : -c->half, (o & 2) ? c->half : -c->half,
                                   (o & 4) ? c->half : -c->half);
      change += c->own();
      children[static_cast<std::size_t>(o)] = std::move(c);
    }
    return children[static_cast<std::size_t>(o)].get();
  }

  int init_threshold(const LioParams& lio) const {
    const auto& v = lio.layer_init_num;
    if (v.empty()) return 5;
    return v[static_cast<std::size_t>(std::min<int>(layer, static_cast<int>(v.size()) - 1))];
  }

  void split_into_children(const LioParams& lio, Counts& change) {
    split = true;
    plane.is_plane = false;
    for (const auto& p : points) child(octant(p.p), change)->insert(p, lio, change);
    points.clear();
    points.shrink_to_fit();
  }

  void fit(const LioParams& lio) {
    plane = map_plane(fit_plane(points, lio.min_eigen_value, lio.min_plane_spread_ratio));
    new_points = 0;
  }

  // Points that are not planar split into the octants below; a line is flat and waits for the
  // points that span it (the next rings, from the next viewpoints), which its octants would share.
  bool should_split(const LioParams& lio) const {
    return !plane.is_plane && !plane.line && layer < lio.max_layer;
  }

  void freeze() {
    frozen = true;
    points.clear();
    points.shrink_to_fit();
    beyond.reset();
  }

  // A plane that stores no more points goes on from the moments of all of them: refitted at every
  // tenth more (the plane of many points moves little), final at max_points_num. One that stops
  // being planar (a passing object, drift) freezes as it was.
  void take_beyond(const CovPoint& p, const LioParams& lio) {
    beyond->moments.add(p.p);
    ++new_points;
    const bool last = beyond->moments.count >= lio.max_points_num;
    if (last || new_points > std::max(lio.plane_update_points,
                                      static_cast<int>(beyond->moments.count) / 10)) {
      const std::optional<MapPlane> refit = refit_map_plane(
          beyond->moments, beyond->reference, beyond->reference_points, lio.min_eigen_value);
      new_points = 0;
      if (!refit) {
        freeze();
        return;
      }
      plane = *refit;
    }
    if (last) freeze();
  }

  // `change` receives what the insert changed in the map's counts.
  void insert(const CovPoint& p, const LioParams& lio, Counts& change) {
    if (split) {
      child(octant(p.p), change)->insert(p, lio, change);
      return;
    }
    if (frozen) return;  // the plane is final; FAST-LIVO2 behaviour (bounded memory)
    const OwnChange own_change(*this, change);
    if (beyond) {
      take_beyond(p, lio);
      return;
    }
    points.push_back(p);
    ++new_points;
    if (!initialized) {
      if (static_cast<int>(points.size()) > init_threshold(lio)) {
        initialized = true;
        fit(lio);
        if (should_split(lio)) split_into_children(lio, change);
      }
      return;
    }
    if (new_points > lio.plane_update_points) {
      fit(lio);
      if (should_split(lio)) {
        split_into_children(lio, change);
        return;
      }
    }
    if (static_cast<int>(points.size()) >= lio.max_points_num) {
      fit(lio);
      freeze();
      return;
    }
    if (static_cast<int>(points.size()) >= lio.max_cov_points) {
      // Store no more: the plane of the stored points (and its covariance) goes on from their
      // moments. Points that are not planar by now (or still a line) freeze, as FAST-LIVO2
      // freezes every node at its last point (splitting them here instead cost the Avia room
      // 8.9 -> 9.8 mm, 3 seeds).
      fit(lio);
      if (!plane.is_plane) {
        freeze();
        return;
      }
      beyond = std::make_unique<Moments>();
      beyond->moments.origin = center;
      for (const CovPoint& q : points) beyond->moments.add(q.p);
      beyond->reference = plane;
      beyond->reference_points = beyond->moments.count;
      points.clear();
      points.shrink_to_fit();
    }
  }

  // Best plane in this subtree for p (highest likelihood passing the gates). best.plane == nullptr
  // means no candidate yet.
  void best_match(const PointQuery& q, double sigma_num, PlaneMatch& best) const {
    const Eigen::Vector3d& p = q.p;
    if (plane.is_plane && !split) {
      // The in-plane extent gate needs only the distance: test it before the variance, which
      // costs a 6x6 quadratic form. Gates compare squares (no square roots).
      const double distance = plane.normal.dot(p) + plane.d;
      const double along = (p - plane.center).squaredNorm() - distance * distance;
      if (along > plane.extent2) return;
      const PlaneResidual r = plane_residual(plane, q);
      const double gate = q.gate_sigmas > 0.0 ? q.gate_sigmas : sigma_num;
      if (!(r.variance > 0.0) || r.distance * r.distance >= gate * gate * r.variance) {
        return;
      }
      // Most points have one candidate: the likelihoods are only needed to choose between two.
      if (best.plane == nullptr ||
          likelihood(r.distance, r.variance) > likelihood(best.distance, best.variance)) {
        best = PlaneMatch{&plane, r.distance, r.variance};
      }
      return;
    }
    for (const auto& c : children) {
      if (c) c->best_match(q, sigma_num, best);
    }
  }

  static double likelihood(double distance, double variance) {
    return std::exp(-0.5 * distance * distance / variance) / std::sqrt(variance);
  }

  void accumulate(Counts& s) const {
    s += own();
    for (const auto& c : children) {
      if (c) c->accumulate(s);
    }
  }
};

VoxelMap::VoxelMap(const LioParams& lio, const MapParams& map) : lio_(lio), map_(map) {}
VoxelMap::~VoxelMap() = default;
VoxelMap::VoxelMap(VoxelMap&&) noexcept = default;
VoxelMap& VoxelMap::operator=(VoxelMap&&) noexcept = default;

void VoxelMap::insert(const std::vector<CovPoint>& points, TaskRunner* runner) {
  ++generation_;
  // Voxels dropped by a slide are freed a batch per scan: freeing them at once was the largest
  // per-frame spike on a drive (tens of thousands of subtrees; on the OS1-128 street a slide
  // every ~8 scans drops ~3 500 voxels, +7 ms on the next frame when freed together).
  const std::size_t retire = std::min(
      retired_.size(), std::max(kRetiredPerInsert, retired_.size() / kRetiredBacklogFraction));
  for (std::size_t i = 0; i < retire; ++i) {
    // Counting the subtree brings it into cache for its destructor.
    Counts freed;
    retired_.back()->accumulate(freed);
    retired_counts_ -= freed;
    retired_.pop_back();
  }
  const double vs = lio_.voxel_size;
  // 1. Bucket the points by root voxel (creating roots), roots numbered in order of first touch.
  //    Keys are computed in parallel; the table lookups run with their slots prefetched some
  //    points ahead, and consecutive points of a voxel (points come in spatial order) reuse the
  //    last lookup.
  const std::size_t n = points.size();
  point_keys_.resize(n);
  const auto compute_keys = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) point_keys_[i] = voxel_key(points[i].p, vs);
  };
  if (runner != nullptr) {
    parallel_for(*runner, n, 2048, compute_keys);
  } else {
    compute_keys(0, n);
  }
  constexpr std::size_t kAhead = 16;
  batch_roots_.clear();
  point_batch_.resize(n);
  VoxelKey last_key;
  std::uint32_t last_batch = kNoBatch;
  for (std::size_t i = 0; i < n; ++i) {
    if (i + kAhead < n) roots_.prefetch(point_keys_[i + kAhead]);
    const VoxelKey& key = point_keys_[i];
    if (last_batch != kNoBatch && key == last_key) {
      point_batch_[i] = last_batch;
      continue;
    }
    auto& root = roots_[key];
    if (!root) {
      root = std::make_unique<Node>();
      root->half = vs / 2;
      root->center = Eigen::Vector3d((static_cast<double>(key.x) + 0.5) * vs,
                                     (static_cast<double>(key.y) + 0.5) * vs,
                                     (static_cast<double>(key.z) + 0.5) * vs);
      live_counts_ += root->own();
    }
    if (root->batch == kNoBatch) {
      root->batch = static_cast<std::uint32_t>(batch_roots_.size());
      batch_roots_.push_back(root.get());
    }
    point_batch_[i] = root->batch;
    last_key = key;
    last_batch = root->batch;
  }
  // 2. Points grouped per root, in scan order within each root (a stable counting sort).
  batch_offsets_.assign(batch_roots_.size() + 1, 0);
  for (const std::uint32_t b : point_batch_) ++batch_offsets_[b + 1];
  for (std::size_t b = 0; b < batch_roots_.size(); ++b) batch_offsets_[b + 1] += batch_offsets_[b];
  batch_order_.resize(points.size());
  batch_cursor_.assign(batch_offsets_.begin(), batch_offsets_.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    batch_order_[batch_cursor_[point_batch_[i]]++] = static_cast<std::uint32_t>(i);
  }
  // 3. Each root's octree takes its points: roots are independent, so they are updated in
  //    parallel, and each sees its points in the same order whatever the thread count. Each
  //    root's task keeps what it changed, summed into the map's counts afterwards.
  batch_change_.assign(batch_roots_.size(), Counts{});
  const auto update_root = [&](std::size_t b) {
    Node* root = batch_roots_[b];
    Counts& change = batch_change_[b];
    for (std::uint32_t k = batch_offsets_[b]; k < batch_offsets_[b + 1]; ++k) {
      root->insert(points[batch_order_[k]], lio_, change);
    }
    root->batch = kNoBatch;
  };
  if (runner != nullptr) {
    runner->run(batch_roots_.size(), update_root);
  } else {
    for (std::size_t b = 0; b < batch_roots_.size(); ++b) update_root(b);
  }
  for (const Counts& change : batch_change_) live_counts_ += change;
}

bool VoxelMap::match(const Eigen::Vector3d& p, const Eigen::Matrix3d& cov, PlaneMatch& out) const {
  PointQuery q;
  q.p = p;
  q.cov = cov;
  Hint hint;
  return match(q, out, hint);
}

bool VoxelMap::match(const PointQuery& q, PlaneMatch& out, Hint& hint) const {
  const Eigen::Vector3d& p = q.p;
  const double vs = lio_.voxel_size;
  const VoxelKey key = voxel_key(p, vs);
  if (hint.generation != generation_ || !(hint.key == key)) {
    hint = Hint{key, roots_.find(key), generation_};
  }
  PlaneMatch m;
  if (hint.root != nullptr) hint.root->best_match(q, lio_.sigma_num, m);
  if (m.plane == nullptr) {
    // Neighbour fallback, in voxel units: the voxels across the faces the point is near.
    const Eigen::Vector3d frac(p.x() / vs - static_cast<double>(key.x),
                               p.y() / vs - static_cast<double>(key.y),
                               p.z() / vs - static_cast<double>(key.z));
    for (int axis = 0; axis < 3; ++axis) {
      int step = 0;
      if (frac[axis] < 0.25) step = -1;
      if (frac[axis] > 0.75) step = 1;
      if (step == 0) continue;
      VoxelKey n = key;
      (axis == 0 ? n.x : axis == 1 ? n.y : n.z) += step;
      if (const Node* root = roots_.find(n)) root->best_match(q, lio_.sigma_num, m);
    }
  }
  if (m.plane == nullptr) return false;
  out = m;
  return true;
}

void VoxelMap::prefetch_root(const Eigen::Vector3d& p) const {
  roots_.prefetch(voxel_key(p, lio_.voxel_size));
}

void VoxelMap::resolve(const Eigen::Vector3d& p, Hint& hint) const {
  const VoxelKey key = voxel_key(p, lio_.voxel_size);
  if (hint.generation != generation_ || !(hint.key == key)) {
    hint = Hint{key, roots_.find(key), generation_};
  }
  if (hint.root != nullptr) {
    // The node's flags and plane: the first three cache lines of the node.
    const char* base = reinterpret_cast<const char*>(hint.root);
    __builtin_prefetch(base);
    __builtin_prefetch(base + 64);
    __builtin_prefetch(base + 128);
  }
}

std::size_t VoxelMap::slide(const Eigen::Vector3d& position) {
  const double vs = lio_.voxel_size;
  const VoxelKey c = voxel_key(position, vs);
  std::size_t removed = 0;
  if (map_.sliding &&
      (!slid_once_ || (position - last_slide_position_).norm() >= map_.slide_threshold_m)) {
    slid_once_ = true;
    last_slide_position_ = position;
    const auto reach = static_cast<std::int64_t>(std::ceil(map_.half_extent_m / vs));
    const std::size_t first = retired_.size();
    removed = roots_.erase_if(
        [&](const VoxelKey& k) {
          return std::abs(k.x - c.x) > reach || std::abs(k.y - c.y) > reach ||
                 std::abs(k.z - c.z) > reach;
        },
        retired_);
    account_retired(first);
  }
  if (roots_.size() > map_.max_voxels) removed += evict_over_budget(c);
  removed_ += removed;
  if (removed > 0) ++generation_;
  return removed;
}

std::size_t VoxelMap::evict_over_budget(const VoxelKey& centre) {
  // Chebyshev distance in voxels (the sliding box's metric): the voxels at or beyond the distance
  // that leaves 90 % of the budget go. One pass to histogram the distances, one to erase; this
  // runs only when the budget is exceeded, and the 10 % margin keeps it from running every scan.
  const std::size_t keep = map_.max_voxels - map_.max_voxels / 10;
  const auto distance = [&](const VoxelKey& k) {
    return std::max({std::abs(k.x - centre.x), std::abs(k.y - centre.y), std::abs(k.z - centre.z)});
  };
  std::vector<std::int64_t> distances;
  distances.reserve(roots_.size());
  roots_.for_each_key([&](const VoxelKey& k) { distances.push_back(distance(k)); });
  const auto cut = distances.begin() + static_cast<std::ptrdiff_t>(keep);
  std::nth_element(distances.begin(), cut, distances.end());
  // Every voxel at distance >= *cut goes (ties included: at most `keep` remain).
  const std::int64_t limit = *cut;
  const std::size_t first = retired_.size();
  const std::size_t evicted =
      roots_.erase_if([&](const VoxelKey& k) { return distance(k) >= limit; }, retired_);
  account_retired(first);
  evicted_ += evicted;
  return evicted;
}

void VoxelMap::account_retired(std::size_t first) {
  // A walk of the dropped subtrees only (about 0.2 us a voxel on a street map); a count kept in
  // every root instead made every node larger and map insertion about 5 % slower.
  for (std::size_t i = first; i < retired_.size(); ++i) {
    Counts dropped;
    retired_[i]->accumulate(dropped);
    live_counts_ -= dropped;
    retired_counts_ += dropped;
  }
}

VoxelMap::Counts& VoxelMap::Counts::operator+=(const Counts& o) {
  nodes += o.nodes;
  planes += o.planes;
  frozen_nodes += o.frozen_nodes;
  stored_points += o.stored_points;
  bytes += o.bytes;
  return *this;
}

VoxelMap::Counts& VoxelMap::Counts::operator-=(const Counts& o) {
  nodes -= o.nodes;
  planes -= o.planes;
  frozen_nodes -= o.frozen_nodes;
  stored_points -= o.stored_points;
  bytes -= o.bytes;
  return *this;
}

VoxelMapStats VoxelMap::make_stats(const Counts& live, const Counts& retired) const {
  VoxelMapStats s;
  s.root_voxels = roots_.size();
  s.nodes = static_cast<std::size_t>(live.nodes);
  s.planes = static_cast<std::size_t>(live.planes);
  s.frozen_nodes = static_cast<std::size_t>(live.frozen_nodes);
  s.stored_points = static_cast<std::size_t>(live.stored_points);
  // Dropped voxels not freed yet still hold memory (counted, not reported as map content).
  s.bytes = roots_.bytes() + static_cast<std::size_t>(live.bytes + retired.bytes) +
            retired_.capacity() * sizeof(std::unique_ptr<Node>);
  s.retired_voxels = retired_.size();
  s.removed_voxels = removed_;
  s.evicted_voxels = evicted_;
  return s;
}

VoxelMapStats VoxelMap::stats() const {
  return make_stats(live_counts_, retired_counts_);
}

VoxelMapStats VoxelMap::count_by_traversal() const {
  Counts live;
  roots_.for_each([&live](const Node& node) { node.accumulate(live); });
  Counts retired;
  for (const auto& node : retired_) node->accumulate(retired);
  return make_stats(live, retired);
}

bool VoxelMap::empty() const {
  return roots_.size() == 0;
}

// ---- RootTable --------------------------------------------------------------------------------

namespace {
constexpr std::size_t kInitialRootSlots = 1024;
}  // namespace

VoxelMap::RootTable::RootTable() {
  entries_.resize(kInitialRootSlots);
}
VoxelMap::RootTable::~RootTable() = default;
VoxelMap::RootTable::RootTable(RootTable&&) noexcept = default;
VoxelMap::RootTable& VoxelMap::RootTable::operator=(RootTable&&) noexcept = default;

VoxelMap::Node* VoxelMap::RootTable::find(const VoxelKey& key) const {
  const std::size_t mask = entries_.size() - 1;
  for (std::size_t i = VoxelKeyHash{}(key)&mask;; i = (i + 1) & mask) {
    const Entry& e = entries_[i];
    if (!e.node) return nullptr;
    if (e.key == key) return e.node.get();
  }
}

void VoxelMap::RootTable::prefetch(const VoxelKey& key) const {
  __builtin_prefetch(&entries_[VoxelKeyHash{}(key) & (entries_.size() - 1)]);
}

std::unique_ptr<VoxelMap::Node>& VoxelMap::RootTable::operator[](const VoxelKey& key) {
  if (2 * (size_ + 1) > entries_.size()) rehash(2 * entries_.size());
  const std::size_t mask = entries_.size() - 1;
  std::size_t i = VoxelKeyHash{}(key)&mask;
  for (; entries_[i].node; i = (i + 1) & mask) {
    if (entries_[i].key == key) return entries_[i].node;
  }
  // The caller fills the new entry (insert() always does): an empty node would end probe runs.
  entries_[i].key = key;
  ++size_;
  return entries_[i].node;
}

void VoxelMap::RootTable::rehash(std::size_t slots) {
  std::vector<Entry> old;
  old.swap(entries_);
  entries_.resize(slots);
  size_ = 0;
  const std::size_t mask = slots - 1;
  for (auto& e : old) {
    if (!e.node) continue;
    std::size_t i = VoxelKeyHash{}(e.key) & mask;
    while (entries_[i].node) i = (i + 1) & mask;
    entries_[i] = std::move(e);
    ++size_;
  }
}

std::size_t VoxelMap::RootTable::erase_if(const std::function<bool(const VoxelKey&)>& remove,
                                          std::vector<std::unique_ptr<Node>>& removed) {
  std::vector<VoxelKey> keys;
  for (const auto& e : entries_) {
    if (e.node && remove(e.key)) keys.push_back(e.key);
  }
  const std::size_t mask = entries_.size() - 1;
  for (const VoxelKey& key : keys) {
    std::size_t i = VoxelKeyHash{}(key)&mask;
    while (!(entries_[i].node && entries_[i].key == key)) i = (i + 1) & mask;  // collected above
    removed.push_back(std::move(entries_[i].node));
    --size_;
    // Backward-shift deletion: linear probing must not leave a hole inside a probe run, so the
    // entries after it that may live at or before the hole move back (no tombstones, no rehash).
    std::size_t hole = i;
    for (std::size_t j = (i + 1) & mask; entries_[j].node; j = (j + 1) & mask) {
      const std::size_t home = VoxelKeyHash{}(entries_[j].key) & mask;
      // Entry j may move into the hole unless its home lies cyclically in (hole, j].
      const bool home_after_hole =
          hole <= j ? (home > hole && home <= j) : (home > hole || home <= j);
      if (home_after_hole) continue;
      entries_[hole] = std::move(entries_[j]);
      hole = j;
    }
  }
  return keys.size();
}

void VoxelMap::RootTable::for_each(const std::function<void(const Node&)>& visit) const {
  for (const auto& e : entries_) {
    if (e.node) visit(*e.node);
  }
}

void VoxelMap::RootTable::for_each_key(const std::function<void(const VoxelKey&)>& visit) const {
  for (const auto& e : entries_) {
    if (e.node) visit(e.key);
  }
}

std::size_t VoxelMap::RootTable::bytes() const {
  return entries_.capacity() * sizeof(Entry);
}

}  // namespace livod::estimator
