#include "tools/sim/moving_objects.hpp"

#include <cmath>
#include <random>

#include "tools/sim/scenario.hpp"

namespace livod::sim {
namespace {

Surface object_surface(float reflectivity, std::uint32_t seed) {
  Surface s;
  s.reflectivity = reflectivity;
  s.texture_scale = 3.0F;
  s.texture_seed = seed;
  return s;
}

// Pedestrian: an upright cylinder of 0.25 m radius, 1.75 m tall.
MovingObject pedestrian(const Eigen::Vector3d& base, const Eigen::Vector3d& velocity, double pace,
                        float reflectivity, std::uint32_t seed) {
  MovingObject o;
  o.shape = MovingObject::Shape::kCylinder;
  o.half = Eigen::Vector3d(0.25, 0.25, 1.75);
  o.start = base;
  o.velocity = velocity;
  o.pace_m = pace;
  o.surface = object_surface(reflectivity, seed);
  return o;
}

// Car: a 4.5 x 1.8 x 1.5 m box.
MovingObject car(const Eigen::Vector3d& centre, double speed, double min_x, double max_x,
                 float reflectivity, std::uint32_t seed) {
  MovingObject o;
  o.shape = MovingObject::Shape::kBox;
  o.half = Eigen::Vector3d(2.25, 0.9, 0.75);
  o.start = centre;
  o.velocity = Eigen::Vector3d(speed, 0.0, 0.0);
  o.wrap_min_x = min_x;
  o.wrap_max_x = max_x;
  o.surface = object_surface(reflectivity, seed);
  return o;
}

}  // namespace

MovingObjects::MovingObjects(std::vector<MovingObject> objects) : objects_(std::move(objects)) {
  shapes_.reserve(objects_.size());
  for (const auto& o : objects_) {
    World w;
    if (o.shape == MovingObject::Shape::kBox) {
      w.add_box(o.start, o.half, o.yaw, o.surface);
      bound_radius_.push_back(o.half.norm());
    } else {
      w.add_cylinder(o.start, o.half.x(), o.half.z(), o.surface);
      bound_radius_.push_back(std::hypot(o.half.x(), 0.5 * o.half.z()));
    }
    w.build();
    shapes_.push_back(std::move(w));
  }
}

Eigen::Vector3d MovingObjects::position(std::size_t i, double time) const {
  const MovingObject& o = objects_[i];
  const double speed = o.velocity.norm();
  if (speed == 0.0) return o.start;
  const Eigen::Vector3d dir = o.velocity / speed;
  const double s = speed * time;
  if (o.pace_m > 0.0) {
    // Back and forth: a triangle wave of period 2 pace.
    const double period = 2.0 * o.pace_m;
    const double u = s - period * std::floor(s / period);
    return o.start + dir * (u <= o.pace_m ? u : period - u);
  }
  const double span = o.wrap_max_x - o.wrap_min_x;
  if (span <= 0.0) return o.start + dir * s;
  Eigen::Vector3d p = o.start + dir * s;
  p.x() = o.wrap_min_x + (p.x() - o.wrap_min_x) - span * std::floor((p.x() - o.wrap_min_x) / span);
  return p;
}

bool MovingObjects::intersect(double time, const Eigen::Vector3d& origin,
                              const Eigen::Vector3d& dir, double t_min, double t_max,
                              Hit& hit) const {
  if (time != cached_time_) {
    cached_time_ = time;
    placed_.clear();
    for (std::size_t i = 0; i < objects_.size(); ++i) {
      const Eigen::Vector3d shift = position(i, time) - objects_[i].start;
      Eigen::Vector3d centre = objects_[i].start + shift;
      if (objects_[i].shape == MovingObject::Shape::kCylinder) {
        centre.z() += 0.5 * objects_[i].half.z();
      }
      placed_.push_back(Placed{static_cast<std::uint32_t>(i), shift, centre});
    }
  }
  bool found = false;
  double best = t_max;
  for (const Placed& o : placed_) {
    // Bounding-sphere rejection first: most objects are nowhere near a given ray.
    const Eigen::Vector3d oc = o.centre - origin;
    const double along = oc.dot(dir);
    const double r = bound_radius_[o.index];
    if (along + r < t_min || along - r > best) continue;
    if ((oc - along * dir).squaredNorm() > r * r) continue;
    Hit h;
    if (shapes_[o.index].intersect(origin - o.shift, dir, t_min, best, h)) {
      best = h.range;
      hit = h;
      hit.point += o.shift;
      hit.primitive = o.index;
      found = true;
    }
  }
  return found;
}

MovingObjects make_moving_objects(WorldKind world, const SceneContent& content, std::uint64_t seed,
                                  double street_length_m) {
  std::vector<MovingObject> objects;
  std::mt19937_64 rng(seed ^ 0x6d6f76696e67ULL);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uint32_t id = 9000;
  const auto reflectivity = [&] { return static_cast<float>(0.15 + 0.6 * unit(rng)); };
  if (world == WorldKind::kStreet) {
    constexpr double kStart = -20.0;  // make_street_world's first metre
    const double end = kStart + street_length_m;
    const auto count = [&](double per_100m) {
      return static_cast<int>(std::lround(per_100m * street_length_m / 100.0));
    };
    // People on the pavements (between the kerb at 7 m and the buildings at >= 10 m), walking
    // 1.1-1.6 m/s along the street and turning back after 15-45 m.
    for (int k = 0, n = count(content.pedestrians); k < n; ++k) {
      const double side = (k % 2 == 0) ? 1.0 : -1.0;
      const Eigen::Vector3d base(kStart + (end - kStart) * unit(rng),
                                 side * (7.8 + 1.5 * unit(rng)), 0.0);
      const double speed = (unit(rng) < 0.5 ? -1.0 : 1.0) * (1.1 + 0.5 * unit(rng));
      objects.push_back(
          pedestrian(base, {speed, 0.0, 0.0}, 15.0 + 30.0 * unit(rng), reflectivity(), id++));
    }
    // Traffic: the oncoming lane (y = -3.5, driving -x) and the far side of our lane (y = +4,
    // overtaking at 12-15 m/s), wrapping around the street.
    for (int k = 0, n = count(content.cars); k < n; ++k) {
      const bool oncoming = k % 2 == 0;
      const double speed = oncoming ? -(8.0 + 6.0 * unit(rng)) : 12.0 + 3.0 * unit(rng);
      const Eigen::Vector3d centre(kStart + (end - kStart) * unit(rng), oncoming ? -3.5 : 4.0,
                                   0.75);
      objects.push_back(car(centre, speed, kStart, end, reflectivity(), id++));
    }
  } else if (world == WorldKind::kRoom) {
    // People pacing between the free centre (the handheld path stays within ~3 m) and the
    // furniture along the walls.
    const auto n = static_cast<int>(std::lround(content.pedestrians));
    for (int k = 0; k < n; ++k) {
      const bool along_y = k % 2 == 0;
      const double side = (k / 2) % 2 == 0 ? 1.0 : -1.0;
      const double pace = along_y ? 4.0 + 2.0 * unit(rng) : 5.0 + 3.0 * unit(rng);
      const double speed = 0.8 + 0.6 * unit(rng);
      const Eigen::Vector3d base = along_y ? Eigen::Vector3d(side * 4.2, -pace / 2, 0.0)
                                           : Eigen::Vector3d(-pace / 2, side * 3.4, 0.0);
      const Eigen::Vector3d velocity =
          along_y ? Eigen::Vector3d(0.0, speed, 0.0) : Eigen::Vector3d(speed, 0.0, 0.0);
      objects.push_back(pedestrian(base, velocity, pace, reflectivity(), id++));
    }
  }
  return MovingObjects(std::move(objects));
}

}  // namespace livod::sim
