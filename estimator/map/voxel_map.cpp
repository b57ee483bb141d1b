#include "estimator/map/voxel_map.hpp"

#include <cmath>

namespace livod::estimator {

VoxelKey voxel_key(const Eigen::Vector3d& p, double voxel_size) {
  return VoxelKey{static_cast<std::int64_t>(std::floor(p.x() / voxel_size)),
                  static_cast<std::int64_t>(std::floor(p.y() / voxel_size)),
                  static_cast<std::int64_t>(std::floor(p.z() / voxel_size))};
}

struct VoxelMap::Node {
  int layer = 0;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // of the node's cube
  double half = 0.0;                                 // half edge of the cube
  std::vector<CovPoint> points;                      // kept until the node freezes
  int new_points = 0;                                // since the last fit
  bool initialized = false;
  bool frozen = false;
  Plane plane;
  std::array<std::unique_ptr<Node>, 8> children;
  bool split = false;

  int octant(const Eigen::Vector3d& p) const {
    return (p.x() >= center.x() ? 1 : 0) | (p.y() >= center.y() ? 2 : 0) |
           (p.z() >= center.z() ? 4 : 0);
  }

  Node* child(int o) {
    if (!children[static_cast<std::size_t>(o)]) {
      auto c = std::make_unique<Node>();
      c->layer = layer + 1;
      c->half = half / 2;
      c->center =
          center + Eigen::Vector3d((o & 1) ? c->half : -c->half, (o & 2) ? c->half : -c->half,
                                   (o & 4) ? c->half : -c->half);
      children[static_cast<std::size_t>(o)] = std::move(c);
    }
    return children[static_cast<std::size_t>(o)].get();
  }

  int init_threshold(const LioParams& lio) const {
    const auto& v = lio.layer_init_num;
    if (v.empty()) return 5;
    return v[static_cast<std::size_t>(std::min<int>(layer, static_cast<int>(v.size()) - 1))];
  }

  void split_into_children(const LioParams& lio) {
    split = true;
    plane.is_plane = false;
    for (const auto& p : points) child(octant(p.p))->insert(p, lio);
    points.clear();
    points.shrink_to_fit();
  }

  void fit(const LioParams& lio) {
    plane = fit_plane(points, lio.min_eigen_value);
    new_points = 0;
  }

  void insert(const CovPoint& p, const LioParams& lio) {
    if (split) {
      child(octant(p.p))->insert(p, lio);
      return;
    }
    if (frozen) return;  // the plane is final; FAST-LIVO2 behaviour (bounded memory)
    points.push_back(p);
    ++new_points;
    if (!initialized) {
      if (static_cast<int>(points.size()) > init_threshold(lio)) {
        initialized = true;
        fit(lio);
        if (!plane.is_plane && layer < lio.max_layer) split_into_children(lio);
      }
      return;
    }
    if (new_points > lio.plane_update_points) {
      fit(lio);
      if (!plane.is_plane && layer < lio.max_layer) {
        split_into_children(lio);
        return;
      }
    }
    if (static_cast<int>(points.size()) >= lio.max_points_num) {
      fit(lio);
      frozen = true;
      points.clear();
      points.shrink_to_fit();
    }
  }

  // Best plane in this subtree for p (highest likelihood passing the gates).
  void best_match(const Eigen::Vector3d& p, const Eigen::Matrix3d& cov, double sigma_num,
                  PlaneMatch& best, double& best_likelihood) const {
    if (plane.is_plane && !split) {
      const PlaneResidual r = plane_residual(plane, p, cov);
      const double along = (p - plane.center).squaredNorm() - r.distance * r.distance;
      const double in_plane = std::sqrt(std::max(0.0, along));
      if (in_plane <= 3.0 * plane.radius && r.variance > 0.0 &&
          std::abs(r.distance) < sigma_num * std::sqrt(r.variance)) {
        const double likelihood =
            std::exp(-0.5 * r.distance * r.distance / r.variance) / std::sqrt(r.variance);
        if (likelihood > best_likelihood) {
          best_likelihood = likelihood;
          best = PlaneMatch{&plane, r.distance, r.variance};
        }
      }
      return;
    }
    for (const auto& c : children) {
      if (c) c->best_match(p, cov, sigma_num, best, best_likelihood);
    }
  }

  void accumulate(VoxelMapStats& s) const {
    ++s.nodes;
    s.bytes += sizeof(Node) + points.capacity() * sizeof(CovPoint);
    s.stored_points += points.size();
    if (plane.is_plane && !split) ++s.planes;
    if (frozen) ++s.frozen_nodes;
    for (const auto& c : children) {
      if (c) c->accumulate(s);
    }
  }
};

VoxelMap::VoxelMap(const LioParams& lio, const MapParams& map) : lio_(lio), map_(map) {}
VoxelMap::~VoxelMap() = default;
VoxelMap::VoxelMap(VoxelMap&&) noexcept = default;
VoxelMap& VoxelMap::operator=(VoxelMap&&) noexcept = default;

void VoxelMap::insert(const std::vector<CovPoint>& points) {
  const double vs = lio_.voxel_size;
  for (const auto& p : points) {
    const VoxelKey key = voxel_key(p.p, vs);
    auto& root = roots_[key];
    if (!root) {
      root = std::make_unique<Node>();
      root->half = vs / 2;
      root->center = Eigen::Vector3d((static_cast<double>(key.x) + 0.5) * vs,
                                     (static_cast<double>(key.y) + 0.5) * vs,
                                     (static_cast<double>(key.z) + 0.5) * vs);
    }
    root->insert(p, lio_);
  }
}

bool VoxelMap::match(const Eigen::Vector3d& p, const Eigen::Matrix3d& cov, PlaneMatch& out) const {
  const double vs = lio_.voxel_size;
  const VoxelKey key = voxel_key(p, vs);
  double best = 0.0;
  PlaneMatch m;
  if (auto it = roots_.find(key); it != roots_.end()) {
    it->second->best_match(p, cov, lio_.sigma_num, m, best);
  }
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
      if (auto it = roots_.find(n); it != roots_.end()) {
        it->second->best_match(p, cov, lio_.sigma_num, m, best);
      }
    }
  }
  if (m.plane == nullptr) return false;
  out = m;
  return true;
}

std::size_t VoxelMap::slide(const Eigen::Vector3d& position) {
  if (!map_.sliding) return 0;
  if (slid_once_ && (position - last_slide_position_).norm() < map_.slide_threshold_m) return 0;
  slid_once_ = true;
  last_slide_position_ = position;
  const double vs = lio_.voxel_size;
  const VoxelKey c = voxel_key(position, vs);
  const auto reach = static_cast<std::int64_t>(std::ceil(map_.half_extent_m / vs));
  std::size_t removed = 0;
  for (auto it = roots_.begin(); it != roots_.end();) {
    const VoxelKey& k = it->first;
    if (std::abs(k.x - c.x) > reach || std::abs(k.y - c.y) > reach || std::abs(k.z - c.z) > reach) {
      it = roots_.erase(it);
      ++removed;
    } else {
      ++it;
    }
  }
  removed_ += removed;
  return removed;
}

VoxelMapStats VoxelMap::stats() const {
  VoxelMapStats s;
  s.root_voxels = roots_.size();
  s.bytes = roots_.bucket_count() * sizeof(void*) +
            roots_.size() * (sizeof(VoxelKey) + sizeof(std::unique_ptr<Node>) + 2 * sizeof(void*));
  for (const auto& [key, node] : roots_) node->accumulate(s);
  s.removed_voxels = removed_;
  return s;
}

bool VoxelMap::empty() const {
  return roots_.empty();
}

}  // namespace livod::estimator
