#include "tools/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace livod::sim {
namespace {

constexpr double kEps = 1e-9;
constexpr std::uint32_t kLeafSize = 4;

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

// Quintic fade: C2-continuous interpolation, so image gradients are smooth.
double fade(double t) {
  return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

double value_noise(const Eigen::Vector3d& p, std::uint32_t seed) {
  const double fx = std::floor(p.x());
  const double fy = std::floor(p.y());
  const double fz = std::floor(p.z());
  const auto ix = static_cast<std::int64_t>(fx);
  const auto iy = static_cast<std::int64_t>(fy);
  const auto iz = static_cast<std::int64_t>(fz);
  const double u = fade(p.x() - fx);
  const double v = fade(p.y() - fy);
  const double w = fade(p.z() - fz);
  double c[2][2][2];
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int d = 0; d < 2; ++d) c[a][b][d] = lattice_value(ix + a, iy + b, iz + d, seed);
  const double x00 = c[0][0][0] + u * (c[1][0][0] - c[0][0][0]);
  const double x10 = c[0][1][0] + u * (c[1][1][0] - c[0][1][0]);
  const double x01 = c[0][0][1] + u * (c[1][0][1] - c[0][0][1]);
  const double x11 = c[0][1][1] + u * (c[1][1][1] - c[0][1][1]);
  const double y0 = x00 + v * (x10 - x00);
  const double y1 = x01 + v * (x11 - x01);
  return y0 + w * (y1 - y0);
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
  if (!primitives_.empty()) build_node(0, static_cast<std::uint32_t>(primitives_.size()));
}

std::uint32_t World::build_node(std::uint32_t first, std::uint32_t count) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Aabb box;
  Aabb centroids;
  for (std::uint32_t i = first; i < first + count; ++i) {
    box.extend(primitives_[order_[i]].box);
    centroids.extend(primitives_[order_[i]].box.center());
  }
  nodes_[index].box = box;
  if (count <= kLeafSize) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  // Median split along the widest centroid axis: balanced and deterministic.
  const Eigen::Vector3d extent = centroids.max - centroids.min;
  int axis = 0;
  if (extent.y() > extent[axis]) axis = 1;
  if (extent.z() > extent[axis]) axis = 2;
  const std::uint32_t mid = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                   [&](std::uint32_t a, std::uint32_t b) {
                     const double ca = primitives_[a].box.center()[axis];
                     const double cb = primitives_[b].box.center()[axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const std::uint32_t left = build_node(first, mid - first);
  const std::uint32_t right = build_node(mid, first + count - mid);
  nodes_[index].first = left;
  nodes_[index].right = right;
  nodes_[index].count = 0;
  return index;
}

bool World::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                      double t_max, Hit& hit) const {
  if (nodes_.empty()) return false;
  const Eigen::Vector3d inv_dir = dir.cwiseInverse();
  bool found = false;
  double best = t_max;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!node.box.intersects(origin, inv_dir, t_min, best)) continue;
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        if (intersect_primitive(primitives_[order_[i]], origin, dir, t_min, best, hit)) {
          best = hit.range;
          hit.primitive = order_[i];
          found = true;
        }
      }
    } else if (top + 2 <= 64) {
      stack[top++] = node.right;
      stack[top++] = node.first;
    }
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
      const Eigen::Vector3d o = p.R_world_prim.transpose() * (origin - p.center);
      const Eigen::Vector3d d = p.R_world_prim.transpose() * dir;
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
      normal = p.R_world_prim * n_local;
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
  // Three octaves of value noise: 1/m, 2.7/m and 7.3/m (scaled per surface). Coarse octaves give
  // large-scale gradients for the pyramid's top levels, fine ones texture for 8x8 patches.
  const Eigen::Vector3d p = point * static_cast<double>(surface.texture_scale);
  double v = 0.0;
  double amplitude = 0.5;
  double frequency = 1.0;
  double norm = 0.0;
  for (int octave = 0; octave < 3; ++octave) {
    v += amplitude * value_noise(p * frequency, surface.texture_seed + 977U * octave);
    norm += amplitude;
    amplitude *= 0.6;
    frequency *= 2.7;
  }
  v /= norm;  // in [0, 1], mean about 0.5
  const double a = 0.5 + static_cast<double>(surface.texture_contrast) * 2.0 * (v - 0.5);
  return static_cast<float>(std::clamp(a, 0.02, 0.98));
}

}  // namespace livod::sim
