#pragma once
// Things that move through a world while the sensors record it: pedestrians and cars. Each object
// is a solid (box or upright cylinder) carried along a straight line, either back and forth
// (people pacing, a car shuttling in a short street) or wrapping around a span (traffic on a long
// street). The static world does not know them; sensors ask the scene, which intersects the world
// and then these at the firing time. Deterministic for a seed.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "tools/sim/world.hpp"

namespace livod::sim {

enum class WorldKind;

struct MovingObject {
  enum class Shape { kBox, kCylinder };
  Shape shape = Shape::kBox;
  Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5);  // box half extents; cylinder (r, r, h)
  double yaw = 0.0;                                       // box heading about z (rad)
  Eigen::Vector3d start = Eigen::Vector3d::Zero();        // box centre / cylinder base at t = 0
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();     // m/s along the path
  // > 0: the object turns back after this distance and paces between start and the far end;
  // 0: it moves on and wraps around within [wrap_min_x, wrap_max_x) (traffic along a street).
  double pace_m = 0.0;
  double wrap_min_x = 0.0;
  double wrap_max_x = 0.0;
  Surface surface;
};

// What a scenario asks for (`scene:` in a scenario file). Counts are per 100 m of street in the
// street world and per room in the room world; the corridor stays empty.
struct SceneContent {
  double pedestrians = 0.0;
  double cars = 0.0;
  bool foliage = false;  // tree crowns and hedges scatter beams inside their volume
};

class MovingObjects {
 public:
  MovingObjects() = default;
  explicit MovingObjects(std::vector<MovingObject> objects);

  // Nearest hit of origin + t dir (t in (t_min, t_max]) with any object at scenario time `time`.
  // Not thread-safe: the objects' positions at the last time asked are cached (a LiDAR fires
  // several rays per firing time, a camera thousands per frame).
  bool intersect(double time, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                 double t_min, double t_max, Hit& hit) const;

  // Where object i is at scenario time `time` (box centre / cylinder base).
  [[nodiscard]] Eigen::Vector3d position(std::size_t i, double time) const;
  [[nodiscard]] const std::vector<MovingObject>& objects() const { return objects_; }
  [[nodiscard]] bool empty() const { return objects_.empty(); }

 private:
  std::vector<MovingObject> objects_;
  std::vector<World> shapes_;  // one single-primitive world per object, at its start position
  std::vector<double> bound_radius_;
  struct Placed {
    std::uint32_t index;
    Eigen::Vector3d shift;   // from the start position
    Eigen::Vector3d centre;  // of the bounding sphere
  };
  mutable double cached_time_ = -1e300;
  mutable std::vector<Placed> placed_;
};

// Pedestrians and cars for a named world (room: people pacing in the ring between the free
// centre and the walls; street: people on the pavements, cars in both lanes).
MovingObjects make_moving_objects(WorldKind world, const SceneContent& content, std::uint64_t seed,
                                  double street_length_m);

}  // namespace livod::sim
