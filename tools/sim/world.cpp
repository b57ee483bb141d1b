#include "tools/sim/world.hpp"

#include <algorithm>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <cmath>
#include <limits>

namespace livod::sim {
namespace {

constexpr double kEps = 1e-9;

// Integer lattice hash -> [0, 1). A small avalanche mix (murmur-style finaliser), deterministic
// on every platform.
double lattice_value(std::int64_t x, std::int64_t y, std::int64_t z, std::uint32_t seed) {
  std::uint64_t h = static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ULL ^
                    static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4FULL ^
                    static_cast<std::uint64_t>(z) * 0x165667B19E3779F9ULL ^
                    (static_cast<std::uint64_t>(seed) << 32);
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDULL;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ULL;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

// The slab test of Aabb::intersects() without branches, for the hot traversal loop: the same
// comparisons as there (a NaN from 0 * inf compares false and leaves the interval unchanged),
// written as selections the compiler turns into min/max instructions, and the empty-interval
// check once at the end (t_min only grows and t_max only shrinks, so that is equivalent).
inline bool slab_entry(const Aabb& box, const Eigen::Vector3d& origin,
                       const Eigen::Vector3d& inv_dir, double t_min, double t_max,
                       double& t_entry) {
  for (int i = 0; i < 3; ++i) {
    const double t0 = (box.min[i] - origin[i]) * inv_dir[i];
    const double t1 = (box.max[i] - origin[i]) * inv_dir[i];
    const double near = t0 > t1 ? t1 : t0;
    const double far = t0 > t1 ? t0 : t1;
    t_min = near > t_min ? near : t_min;
    t_max = far < t_max ? far : t_max;
  }
  t_entry = t_min;
  return !(t_min > t_max);
}

// slab_entry() for both children of an inner node at once: bit 0 set when the ray meets the left
// box, bit 1 the right one, their entry distances in `entry`. With SSE2 the two lanes run
// together; minpd/maxpd select exactly as the ternaries of slab_entry() do (the second operand
// when a NaN is involved), so the results are bit for bit the same.
inline int slab_entry_pair(const double (&child_min)[3][2], const double (&child_max)[3][2],
                           const Eigen::Vector3d& origin, const Eigen::Vector3d& inv_dir,
                           double t_min, double t_max, double (&entry)[2]) {
#if defined(__SSE2__)
  __m128d lo = _mm_set1_pd(t_min);
  __m128d hi = _mm_set1_pd(t_max);
  for (int i = 0; i < 3; ++i) {
    const __m128d o = _mm_set1_pd(origin[i]);
    const __m128d inv = _mm_set1_pd(inv_dir[i]);
    const __m128d t0 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(child_min[i]), o), inv);
    const __m128d t1 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(child_max[i]), o), inv);
    const __m128d near = _mm_min_pd(t1, t0);  // t0 > t1 ? t1 : t0
    const __m128d far = _mm_max_pd(t0, t1);   // t0 > t1 ? t0 : t1
    lo = _mm_max_pd(near, lo);                // near > t_min ? near : t_min
    hi = _mm_min_pd(far, hi);                 // far < t_max ? far : t_max
  }
  _mm_storeu_pd(entry, lo);
  return _mm_movemask_pd(_mm_cmpngt_pd(lo, hi));  // !(t_min > t_max) per lane
#else
  int mask = 0;
  for (int lane = 0; lane < 2; ++lane) {
    double lo = t_min;
    double hi = t_max;
    for (int i = 0; i < 3; ++i) {
      const double t0 = (child_min[i][lane] - origin[i]) * inv_dir[i];
      const double t1 = (child_max[i][lane] - origin[i]) * inv_dir[i];
      const double near = t0 > t1 ? t1 : t0;
      const double far = t0 > t1 ? t0 : t1;
      lo = near > lo ? near : lo;
      hi = far < hi ? far : hi;
    }
    entry[lane] = lo;
    if (!(lo > hi)) mask |= 1 << lane;
  }
  return mask;
#endif
}

constexpr int kSahDepth = 32;
constexpr std::uint32_t kMedianLeafSize = 4;

double surface_area(const Aabb& box) {
  const Eigen::Vector3d e = (box.max - box.min).cwiseMax(0.0);
  return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
}

// Quintic fade: C2-continuous interpolation, so image gradients are smooth.
double fade(double t) {
  return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// The 8 lattice values around a cell, index a*4 + b*2 + d for the corner offsets (a, b, d).
void lattice_corners(std::int64_t ix, std::int64_t iy, std::int64_t iz, std::uint32_t seed,
                     double (&c)[8]) {
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int d = 0; d < 2; ++d)
        c[a * 4 + b * 2 + d] = lattice_value(ix + a, iy + b, iz + d, seed);
}

// Trilinear blend of the corners with the faded cell coordinates.
double blend(const double (&c)[8], double u, double v, double w) {
  const double x00 = c[0] + u * (c[4] - c[0]);
  const double x10 = c[2] + u * (c[6] - c[2]);
  const double x01 = c[1] + u * (c[5] - c[1]);
  const double x11 = c[3] + u * (c[7] - c[3]);
  const double y0 = x00 + v * (x10 - x00);
  const double y1 = x01 + v * (x11 - x01);
  return y0 + w * (y1 - y0);
}

// Value noise at p; `cell` (optional) caches the corners of the last cell looked up.
double value_noise(const Eigen::Vector3d& p, std::uint32_t seed, AlbedoCache::Cell* cell) {
  const double fx = std::floor(p.x());
  const double fy = std::floor(p.y());
  const double fz = std::floor(p.z());
  const auto ix = static_cast<std::int64_t>(fx);
  const auto iy = static_cast<std::int64_t>(fy);
  const auto iz = static_cast<std::int64_t>(fz);
  const double u = fade(p.x() - fx);
  const double v = fade(p.y() - fy);
  const double w = fade(p.z() - fz);
  if (cell == nullptr) {
    double c[8];
    lattice_corners(ix, iy, iz, seed, c);
    return blend(c, u, v, w);
  }
  if (!cell->valid || cell->x != ix || cell->y != iy || cell->z != iz || cell->seed != seed) {
    lattice_corners(ix, iy, iz, seed, cell->corner);
    cell->valid = true;
    cell->x = ix;
    cell->y = iy;
    cell->z = iz;
    cell->seed = seed;
  }
  return blend(cell->corner, u, v, w);
}

float albedo_of(const Surface& surface, const Eigen::Vector3d& point, AlbedoCache* cache) {
  // Three octaves of value noise: 1/m, 2.7/m and 7.3/m (scaled per surface). Coarse octaves give
  // large-scale gradients for the pyramid's top levels, fine ones texture for 8x8 patches.
  const Eigen::Vector3d p = point * static_cast<double>(surface.texture_scale);
  double v = 0.0;
  double amplitude = 0.5;
  double frequency = 1.0;
  double norm = 0.0;
  for (int octave = 0; octave < AlbedoCache::kOctaves; ++octave) {
    v += amplitude * value_noise(p * frequency, surface.texture_seed + 977U * octave,
                                 cache != nullptr ? &cache->cells[octave] : nullptr);
    norm += amplitude;
    amplitude *= 0.6;
    frequency *= 2.7;
  }
  v /= norm;  // in [0, 1], mean about 0.5
  const double a = 0.5 + static_cast<double>(surface.texture_contrast) * 2.0 * (v - 0.5);
  return static_cast<float>(std::clamp(a, 0.02, 0.98));
}

}  // namespace

bool Aabb::intersects(const Eigen::Vector3d& origin, const Eigen::Vector3d& inv_dir, double t_min,
                      double t_max) const {
  for (int i = 0; i < 3; ++i) {
    double t0 = (min[i] - origin[i]) * inv_dir[i];
    double t1 = (max[i] - origin[i]) * inv_dir[i];
    if (t0 > t1) std::swap(t0, t1);
    // NaN (0 * inf for a ray in the slab plane) compares false and leaves the interval unchanged.
    if (t0 > t_min) t_min = t0;
    if (t1 < t_max) t_max = t1;
    if (t_min > t_max) return false;
  }
  return true;
}

void World::add_box(const Eigen::Vector3d& center, const Eigen::Vector3d& half, double yaw,
                    const Surface& surface) {
  Primitive p;
  p.kind = Kind::kBox;
  p.center = center;
  p.half = half;
  p.R_world_prim = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.axis_aligned = p.R_world_prim == Eigen::Matrix3d::Identity();
  p.surface = static_cast<std::uint32_t>(surfaces_.size());
  surfaces_.push_back(surface);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                                 (i & 4) ? half.z() : -half.z());
    p.box.extend(center + p.R_world_prim * corner);
  }
  primitives_.push_back(p);
}

void World::add_cylinder(const Eigen::Vector3d& base_center, double radius, double height,
                         const Surface& surface) {
  Primitive p;
  p.kind = Kind::kCylinder;
  p.center = base_center;
  p.radius = radius;
  p.half = Eigen::Vector3d(radius, radius, height);
  p.surface = static_cast<std::uint32_t>(surfaces_.size());
  surfaces_.push_back(surface);
  p.box.extend(base_center - Eigen::Vector3d(radius, radius, 0.0));
  p.box.extend(base_center + Eigen::Vector3d(radius, radius, height));
  primitives_.push_back(p);
}

void World::add_sphere(const Eigen::Vector3d& center, double radius, const Surface& surface) {
  Primitive p;
  p.kind = Kind::kSphere;
  p.center = center;
  p.radius = radius;
  p.surface = static_cast<std::uint32_t>(surfaces_.size());
  surfaces_.push_back(surface);
  p.box.extend(center - Eigen::Vector3d::Constant(radius));
  p.box.extend(center + Eigen::Vector3d::Constant(radius));
  primitives_.push_back(p);
}

void World::build() {
  order_.resize(primitives_.size());
  for (std::uint32_t i = 0; i < order_.size(); ++i) order_[i] = i;
  nodes_.clear();
  nodes_.reserve(2 * primitives_.size() + 1);
  bounds_ = Aabb{};
  for (const auto& p : primitives_) bounds_.extend(p.box);
  if (!primitives_.empty()) build_node(0, static_cast<std::uint32_t>(primitives_.size()), 0);
}

std::uint32_t World::build_node(std::uint32_t first, std::uint32_t count, int depth) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Aabb box;
  for (std::uint32_t i = first; i < first + count; ++i) box.extend(primitives_[order_[i]].box);
  nodes_[index].box = box;
  // Surface-area heuristic: the split minimising the expected primitive tests of a random ray,
  // each child weighted by the probability (area ratio) that a ray through this node enters it.
  // Walls, floors and roads span a whole world; the heuristic gives them nodes of their own
  // instead of inflating every box they share, so rays visit far fewer primitives.
  constexpr double kTraversalCost = 0.5;          // one box test relative to one primitive test
  double best_cost = static_cast<double>(count);  // a leaf
  int best_axis = -1;
  std::uint32_t best_left = 0;
  std::vector<std::uint32_t> sorted(order_.begin() + first, order_.begin() + first + count);
  std::vector<double> left_area(count);
  const double parent_area = surface_area(box);
  // Past kSahDepth the heuristic hands over to median splits, which bound the depth (and so the
  // traversal stack) by log2 of the primitive count.
  const bool sah = depth < kSahDepth;
  for (int axis = 0; sah && axis < 3 && count > 1 && parent_area > 0.0; ++axis) {
    sort_by_centroid(sorted, axis);
    Aabb left;
    for (std::uint32_t i = 0; i < count; ++i) {
      left.extend(primitives_[sorted[i]].box);
      left_area[i] = surface_area(left);
    }
    Aabb right;
    for (std::uint32_t n_right = 1; n_right < count; ++n_right) {
      right.extend(primitives_[sorted[count - n_right]].box);
      const std::uint32_t n_left = count - n_right;
      const double cost =
          kTraversalCost +
          (left_area[n_left - 1] * n_left + surface_area(right) * n_right) / parent_area;
      if (cost < best_cost) {
        best_cost = cost;
        best_axis = axis;
        best_left = n_left;
      }
    }
  }
  if (!sah && count > kMedianLeafSize) {
    // Median split along the widest centroid extent.
    Aabb centroids;
    for (const std::uint32_t id : sorted) centroids.extend(primitives_[id].box.center());
    const Eigen::Vector3d extent = centroids.max - centroids.min;
    best_axis = 0;
    if (extent.y() > extent[best_axis]) best_axis = 1;
    if (extent.z() > extent[best_axis]) best_axis = 2;
    best_left = count / 2;
  }
  if (best_axis < 0 || count <= 1) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  sort_by_centroid(sorted, best_axis);
  std::copy(sorted.begin(), sorted.end(), order_.begin() + first);
  const std::uint32_t left_child = build_node(first, best_left, depth + 1);
  const std::uint32_t right_child = build_node(first + best_left, count - best_left, depth + 1);
  Node& node = nodes_[index];
  node.first = left_child;
  node.right = right_child;
  node.count = 0;
  for (int i = 0; i < 3; ++i) {
    node.child_min[i][0] = nodes_[left_child].box.min[i];
    node.child_min[i][1] = nodes_[right_child].box.min[i];
    node.child_max[i][0] = nodes_[left_child].box.max[i];
    node.child_max[i][1] = nodes_[right_child].box.max[i];
  }
  return index;
}

void World::sort_by_centroid(std::vector<std::uint32_t>& ids, int axis) const {
  // Ties broken by index: the tree, and so the traversal order, is the same on every platform.
  std::sort(ids.begin(), ids.end(), [&](std::uint32_t a, std::uint32_t b) {
    const double ca = primitives_[a].box.center()[axis];
    const double cb = primitives_[b].box.center()[axis];
    return ca < cb || (ca == cb && a < b);
  });
}

bool World::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                      double t_max, Hit& hit) const {
  if (nodes_.empty()) return false;
  const Eigen::Vector3d inv_dir = dir.cwiseInverse();
  bool found = false;
  double best = t_max;
  // Front to back: the nearer child is visited next and the farther one deferred on the stack;
  // a deferred node is skipped once a hit lies before its entry distance. Node ids and entry
  // distances live in separate arrays (same-size stores and loads forward cheaply).
  constexpr int kStackSize = 128;
  std::uint32_t deferred_node[kStackSize];
  double deferred_entry[kStackSize];
  int top = 0;
  double entry = 0.0;
  if (!slab_entry(nodes_[0].box, origin, inv_dir, t_min, best, entry)) return false;
  std::uint32_t current = 0;
  for (;;) {
    const Node& node = nodes_[current];
    bool descend = false;
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        if (intersect_primitive(primitives_[order_[i]], origin, dir, t_min, best, hit)) {
          best = hit.range;
          hit.primitive = order_[i];
          found = true;
        }
      }
    } else {
      double entries[2];
      const int met =
          slab_entry_pair(node.child_min, node.child_max, origin, inv_dir, t_min, best, entries);
      const bool left = (met & 1) != 0;
      const bool right = (met & 2) != 0;
      const double entry_left = entries[0];
      const double entry_right = entries[1];
      if (left && right) {
        const bool left_first = entry_left <= entry_right;
        // The stack holds at most the tree depth: below kSahDepth + log2(primitives).
        if (top < kStackSize) {
          deferred_node[top] = left_first ? node.right : node.first;
          deferred_entry[top] = left_first ? entry_right : entry_left;
          ++top;
        }
        current = left_first ? node.first : node.right;
        descend = true;
      } else if (left || right) {
        current = left ? node.first : node.right;
        descend = true;
      }
    }
    if (descend) continue;
    // Next deferred node still in front of the best hit.
    while (top > 0 && deferred_entry[top - 1] > best) --top;
    if (top == 0) break;
    current = deferred_node[--top];
  }
  return found;
}

bool World::intersect_primitive(const Primitive& p, const Eigen::Vector3d& origin,
                                const Eigen::Vector3d& dir, double t_min, double t_max,
                                Hit& hit) const {
  double t = std::numeric_limits<double>::infinity();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  switch (p.kind) {
    case Kind::kBox: {
      // Most boxes are axis-aligned: skip the frame change (identity products are exact anyway).
      const Eigen::Vector3d o =
          p.axis_aligned ? Eigen::Vector3d(origin - p.center)
                         : Eigen::Vector3d(p.R_world_prim.transpose() * (origin - p.center));
      const Eigen::Vector3d d =
          p.axis_aligned ? dir : Eigen::Vector3d(p.R_world_prim.transpose() * dir);
      double t_near = -std::numeric_limits<double>::infinity();
      double t_far = std::numeric_limits<double>::infinity();
      int near_axis = 0;
      int far_axis = 0;
      for (int i = 0; i < 3; ++i) {
        if (std::abs(d[i]) < kEps) {
          if (o[i] < -p.half[i] || o[i] > p.half[i]) return false;
          continue;
        }
        double t0 = (-p.half[i] - o[i]) / d[i];
        double t1 = (p.half[i] - o[i]) / d[i];
        if (t0 > t1) std::swap(t0, t1);
        if (t0 > t_near) {
          t_near = t0;
          near_axis = i;
        }
        if (t1 < t_far) {
          t_far = t1;
          far_axis = i;
        }
        if (t_near > t_far) return false;
      }
      int axis = near_axis;
      t = t_near;
      if (t <= t_min) {  // origin inside the box: the exit face is what the ray sees
        t = t_far;
        axis = far_axis;
      }
      Eigen::Vector3d n_local = Eigen::Vector3d::Zero();
      n_local[axis] = d[axis] > 0 ? -1.0 : 1.0;
      normal = p.axis_aligned ? n_local : Eigen::Vector3d(p.R_world_prim * n_local);
      break;
    }
    case Kind::kCylinder: {
      const Eigen::Vector3d o = origin - p.center;
      const double height = p.half.z();
      // Side: |o_xy + t d_xy| = r
      const double a = dir.x() * dir.x() + dir.y() * dir.y();
      if (a > kEps) {
        const double b = o.x() * dir.x() + o.y() * dir.y();
        const double c = o.x() * o.x() + o.y() * o.y() - p.radius * p.radius;
        const double disc = b * b - a * c;
        if (disc >= 0.0) {
          const double sq = std::sqrt(disc);
          for (const double root : {(-b - sq) / a, (-b + sq) / a}) {
            const double z = o.z() + root * dir.z();
            if (root > t_min && root < t && z >= 0.0 && z <= height) {
              t = root;
              normal =
                  Eigen::Vector3d(o.x() + root * dir.x(), o.y() + root * dir.y(), 0.0) / p.radius;
              break;
            }
          }
        }
      }
      // Caps
      if (std::abs(dir.z()) > kEps) {
        for (const double cap_z : {0.0, height}) {
          const double root = (cap_z - o.z()) / dir.z();
          if (root > t_min && root < t) {
            const double x = o.x() + root * dir.x();
            const double y = o.y() + root * dir.y();
            if (x * x + y * y <= p.radius * p.radius) {
              t = root;
              normal = Eigen::Vector3d(0.0, 0.0, cap_z == 0.0 ? -1.0 : 1.0);
            }
          }
        }
      }
      break;
    }
    case Kind::kSphere: {
      const Eigen::Vector3d o = origin - p.center;
      const double b = o.dot(dir);
      const double c = o.squaredNorm() - p.radius * p.radius;
      const double disc = b * b - c;
      if (disc < 0.0) return false;
      const double sq = std::sqrt(disc);
      t = -b - sq;
      if (t <= t_min) t = -b + sq;
      normal = (o + t * dir) / p.radius;
      break;
    }
  }
  if (!(t > t_min && t <= t_max)) return false;
  if (normal.dot(dir) > 0.0) normal = -normal;
  hit.range = t;
  hit.point = origin + t * dir;
  hit.normal = normal;
  hit.surface = &surfaces_[p.surface];
  return true;
}

float World::albedo(const Surface& surface, const Eigen::Vector3d& point) {
  return albedo_of(surface, point, nullptr);
}

float World::albedo(const Surface& surface, const Eigen::Vector3d& point, AlbedoCache& cache) {
  return albedo_of(surface, point, &cache);
}

}  // namespace livod::sim
