#pragma once
// Synthetic worlds for the simulator: simple solids (oriented boxes, vertical cylinders, spheres)
// with a reflectivity and a procedural texture, and fast ray casting over them through a bounding
// volume hierarchy. Everything is deterministic and in double precision; the world frame is
// z up.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace livod::sim {

struct Surface {
  float reflectivity = 0.5F;   // 0..1, what a LiDAR reports (scaled by the sensor model)
  float texture_scale = 1.0F;  // spatial frequency multiplier of the albedo texture (1/m)
  float texture_contrast = 0.35F;
  std::uint32_t texture_seed = 1;
  // > 0: foliage. The solid is a volume of leaves a LiDAR beam enters and ends in after an
  // exponentially distributed depth of this mean (lidar_return.cpp), or leaves again; cameras see
  // its surface.
  float foliage_free_path_m = 0.0F;
};

struct Hit {
  double range = 0.0;  // distance along the unit ray
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit, facing the ray origin
  const Surface* surface = nullptr;
  std::uint32_t primitive = 0;
};

// An axis-aligned bounding box.
struct Aabb {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(1e300);
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-1e300);
  void extend(const Aabb& o) {
    min = min.cwiseMin(o.min);
    max = max.cwiseMax(o.max);
  }
  void extend(const Eigen::Vector3d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  [[nodiscard]] Eigen::Vector3d center() const { return 0.5 * (min + max); }
  // Slab test; returns the entry distance in [t_min, t_max] or false.
  [[nodiscard]] bool intersects(const Eigen::Vector3d& origin, const Eigen::Vector3d& inv_dir,
                                double t_min, double t_max) const;
};

// The lattice values of the value-noise cells an albedo lookup used last, one cell per octave.
// Neighbouring pixels mostly fall into the same cells, so a renderer passes one cache through a
// frame; albedo() returns exactly the same value with or without it.
struct AlbedoCache {
  static constexpr int kOctaves = 3;
  struct Cell {
    bool valid = false;
    std::int64_t x = 0, y = 0, z = 0;
    std::uint32_t seed = 0;
    double corner[8] = {};  // lattice values, index a*4 + b*2 + d for offsets (a, b, d)
  };
  Cell cells[kOctaves];
};

class World {
 public:
  // A box of half extents `half` centred at `center`, rotated by `yaw` (rad) about z.
  void add_box(const Eigen::Vector3d& center, const Eigen::Vector3d& half, double yaw,
               const Surface& surface);
  // A vertical cylinder (pole, trunk) standing on base_center, capped at both ends.
  void add_cylinder(const Eigen::Vector3d& base_center, double radius, double height,
                    const Surface& surface);
  void add_sphere(const Eigen::Vector3d& center, double radius, const Surface& surface);

  // Builds the bounding volume hierarchy; call after the last add_*() and before intersect().
  void build();

  // Nearest hit along origin + t * dir (dir unit length) with t in (t_min, t_max].
  bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                 double t_max, Hit& hit) const;

  // Grey-level albedo in [0, 1] of the surface at a world point: smooth multi-octave value noise,
  // rich enough in gradient for photometric tracking, identical for every viewpoint.
  [[nodiscard]] static float albedo(const Surface& surface, const Eigen::Vector3d& point);
  [[nodiscard]] static float albedo(const Surface& surface, const Eigen::Vector3d& point,
                                    AlbedoCache& cache);

  [[nodiscard]] std::size_t primitive_count() const { return primitives_.size(); }
  [[nodiscard]] const Aabb& bounds() const { return bounds_; }

 private:
  enum class Kind : std::uint8_t { kBox, kCylinder, kSphere };
  struct Primitive {
    Kind kind = Kind::kBox;
    Eigen::Vector3d center = Eigen::Vector3d::Zero();  // box/sphere centre, cylinder base centre
    Eigen::Vector3d half = Eigen::Vector3d::Zero();    // box half extents; (r, r, h) cylinder
    Eigen::Matrix3d R_world_prim = Eigen::Matrix3d::Identity();
    bool axis_aligned = true;  // R_world_prim is exactly the identity: no frame change needed
    double radius = 0.0;
    std::uint32_t surface = 0;
    Aabb box;
  };
  struct Node {
    Aabb box;
    std::uint32_t first = 0;  // leaf: first primitive index in order_; inner: left child index
    std::uint32_t count = 0;  // leaf: primitive count; 0 for inner nodes
    std::uint32_t right = 0;  // inner: right child index
    // Inner nodes: the children's boxes per axis, [axis][0] left, [axis][1] right, so that the
    // traversal tests both with one pair of two-lane operations.
    alignas(16) double child_min[3][2] = {};
    alignas(16) double child_max[3][2] = {};
  };

  bool intersect_primitive(const Primitive& p, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& dir, double t_min, double t_max, Hit& hit) const;
  std::uint32_t build_node(std::uint32_t first, std::uint32_t count, int depth);
  void sort_by_centroid(std::vector<std::uint32_t>& ids, int axis) const;

  std::vector<Surface> surfaces_;
  std::vector<Primitive> primitives_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
  Aabb bounds_;
};

}  // namespace livod::sim
