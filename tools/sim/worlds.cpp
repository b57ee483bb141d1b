#include "tools/sim/worlds.hpp"

#include <random>

namespace livod::sim {
namespace {

Surface surface(float reflectivity, float texture_scale, std::uint32_t seed,
                float contrast = 0.35F) {
  Surface s;
  s.reflectivity = reflectivity;
  s.texture_scale = texture_scale;
  s.texture_seed = seed;
  s.texture_contrast = contrast;
  return s;
}

}  // namespace

World make_room_world(std::uint64_t seed, const WorldOptions& options) {
  World w;
  constexpr double kHalfX = 6.0;
  constexpr double kHalfY = 4.5;
  constexpr double kHeight = 3.0;
  constexpr double kWall = 0.1;
  // Floor, ceiling and walls as thin slabs (their inner faces are what sensors see).
  w.add_box({0, 0, -kWall}, {kHalfX + kWall, kHalfY + kWall, kWall}, 0.0, surface(0.3F, 2.0F, 1));
  w.add_box({0, 0, kHeight + kWall}, {kHalfX + kWall, kHalfY + kWall, kWall}, 0.0,
            surface(0.6F, 1.5F, 2));
  w.add_box({kHalfX + kWall, 0, kHeight / 2}, {kWall, kHalfY + kWall, kHeight / 2}, 0.0,
            surface(0.5F, 1.7F, 3));
  w.add_box({-kHalfX - kWall, 0, kHeight / 2}, {kWall, kHalfY + kWall, kHeight / 2}, 0.0,
            surface(0.5F, 1.7F, 4));
  w.add_box({0, kHalfY + kWall, kHeight / 2}, {kHalfX + kWall, kWall, kHeight / 2}, 0.0,
            surface(0.45F, 1.9F, 5));
  w.add_box({0, -kHalfY - kWall, kHeight / 2}, {kHalfX + kWall, kWall, kHeight / 2}, 0.0,
            surface(0.45F, 1.9F, 6));

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Furniture in a ring between 3.2 m from the centre and the walls.
  int placed = 0;
  for (int attempt = 0; attempt < 400 && placed < 18; ++attempt) {
    const double hx = 0.2 + 0.6 * unit(rng);
    const double hy = 0.2 + 0.6 * unit(rng);
    const double hz = 0.2 + 0.8 * unit(rng);
    const double x = (kHalfX - hx - 0.05) * (2 * unit(rng) - 1);
    const double y = (kHalfY - hy - 0.05) * (2 * unit(rng) - 1);
    if (std::abs(x) < 3.2 + hx && std::abs(y) < 2.4 + hy) continue;  // keep the centre free
    const double yaw = 0.8 * (unit(rng) - 0.5);
    w.add_box({x, y, hz}, {hx, hy, hz}, yaw,
              surface(static_cast<float>(0.2 + 0.7 * unit(rng)), 3.0F,
                      100U + static_cast<std::uint32_t>(placed)));
    ++placed;
  }
  w.add_cylinder({4.5, 3.2, 0.0}, 0.25, kHeight, surface(0.7F, 4.0F, 60));
  w.add_cylinder({-4.6, -3.1, 0.0}, 0.2, kHeight, surface(0.7F, 4.0F, 61));
  // Wall-mounted boxes (shelves, frames, radiators) on every wall at varied heights and depths:
  // a narrow-field LiDAR facing any wall still sees structure in all three directions.
  std::uint32_t id = 70;
  for (int wall = 0; wall < 4; ++wall) {
    const bool along_x = wall < 2;  // walls at y = +-kHalfY run along x
    const double sign = (wall % 2 == 0) ? 1.0 : -1.0;
    const double length = along_x ? kHalfX : kHalfY;
    for (int k = 0; k < 4; ++k) {
      const double s_pos = (-0.75 + 0.5 * k) * length + 0.4 * (unit(rng) - 0.5);
      const double depth = 0.1 + 0.25 * unit(rng);
      const double width = 0.3 + 0.6 * unit(rng);
      const double height = 0.2 + 0.5 * unit(rng);
      const double z = 0.6 + 1.8 * unit(rng);
      const Eigen::Vector3d half =
          along_x ? Eigen::Vector3d(width, depth, height) : Eigen::Vector3d(depth, width, height);
      const Eigen::Vector3d centre = along_x ? Eigen::Vector3d(s_pos, sign * (kHalfY - depth), z)
                                             : Eigen::Vector3d(sign * (kHalfX - depth), s_pos, z);
      w.add_box(centre, half, 0.0, surface(static_cast<float>(0.3 + 0.6 * unit(rng)), 5.0F, id++));
    }
  }
  if (options.foliage) {
    // Potted plants in the four corners: a pot and a leafy crown of 0.4-0.55 m radius.
    Surface leaves = surface(0.45F, 6.0F, 90);
    leaves.foliage_free_path_m = 0.5F * kFoliageFreePathM;  // denser than a street tree
    for (const double sx : {-1.0, 1.0}) {
      for (const double sy : {-1.0, 1.0}) {
        const Eigen::Vector3d base(sx * (kHalfX - 0.6), sy * (kHalfY - 0.6), 0.0);
        w.add_cylinder(base, 0.2, 0.4, surface(0.3F, 4.0F, 91));
        w.add_sphere(base + Eigen::Vector3d(0, 0, 1.0), 0.4 + 0.15 * (sx > 0 ? 1.0 : 0.0), leaves);
      }
    }
  }
  w.build();
  return w;
}

World make_corridor_world() {
  World w;
  constexpr double kStart = -5.0;
  constexpr double kLength = 80.0;
  constexpr double kHalfWidth = 1.2;
  constexpr double kHeight = 3.0;
  constexpr double kWall = 0.1;
  const double cx = kStart + kLength / 2;
  const double hx = kLength / 2 + kWall;
  // Uniform walls: no geometric feature along x. (The texture still lets a camera see motion.)
  w.add_box({cx, 0, -kWall}, {hx, kHalfWidth + kWall, kWall}, 0.0, surface(0.3F, 2.0F, 11));
  w.add_box({cx, 0, kHeight + kWall}, {hx, kHalfWidth + kWall, kWall}, 0.0,
            surface(0.6F, 2.0F, 12));
  w.add_box({cx, kHalfWidth + kWall, kHeight / 2}, {hx, kWall, kHeight / 2}, 0.0,
            surface(0.5F, 2.0F, 13));
  w.add_box({cx, -kHalfWidth - kWall, kHeight / 2}, {hx, kWall, kHeight / 2}, 0.0,
            surface(0.5F, 2.0F, 14));
  w.build();
  return w;
}

World make_corridor_side_rooms_world() {
  World w;
  constexpr double kStart = -5.0;
  constexpr double kLength = 80.0;
  constexpr double kHalfWidth = 1.2;
  constexpr double kHeight = 3.0;
  constexpr double kWall = 0.1;
  constexpr double kThin = 0.02;        // half thickness of the left wall and the rooms' walls
  constexpr double kDoorSpacing = 6.0;  // a doorway every 6 m, the first at x = 3
  constexpr double kDoorWidth = 1.0;
  constexpr double kRoomLength = 2.5;  // along x, ending flush with its doorway's far jamb
  constexpr double kRoomDepth = 3.0;   // along +y, behind the wall
  const double cx = kStart + kLength / 2;
  const double hx = kLength / 2 + kWall;
  // Floor and ceiling cover the rooms too.
  const double y_far = kHalfWidth + 2 * kThin + kRoomDepth;
  const double floor_cy = (y_far - kHalfWidth) / 2;
  const double floor_hy = (y_far + kHalfWidth) / 2 + kWall;
  w.add_box({cx, floor_cy, -kWall}, {hx, floor_hy, kWall}, 0.0, surface(0.3F, 2.0F, 11));
  w.add_box({cx, floor_cy, kHeight + kWall}, {hx, floor_hy, kWall}, 0.0, surface(0.6F, 2.0F, 12));
  // The right wall (-y) is uniform, as in the featureless corridor.
  w.add_box({cx, -kHalfWidth - kWall, kHeight / 2}, {hx, kWall, kHeight / 2}, 0.0,
            surface(0.5F, 2.0F, 14));
  // The left wall (+y): thin segments between doorways (their jambs are 4 cm: nothing to fit a
  // plane to), a room behind each doorway extending back (-x) from it. A LiDAR looking forward
  // along the corridor sees a room's far side wall (flush with the doorway's far jamb) only as a
  // sliver through the doorway at grazing angles, and never its near side wall, which faces +x.
  // A LiDAR looking sideways sees into the room as it passes.
  const double y_wall = kHalfWidth + kThin;
  double x = kStart - kWall;
  std::uint32_t id = 100;
  for (double door = 3.0; door + kDoorWidth < kStart + kLength; door += kDoorSpacing) {
    w.add_box({(x + door) / 2, y_wall, kHeight / 2}, {(door - x) / 2, kThin, kHeight / 2}, 0.0,
              surface(0.5F, 2.0F, id++));
    const double room_x1 = door + kDoorWidth;
    const double room_x0 = room_x1 - kRoomLength;
    const double room_y = y_wall + kThin + kRoomDepth / 2;
    w.add_box({room_x0 - kThin, room_y, kHeight / 2}, {kThin, kRoomDepth / 2 + kThin, kHeight / 2},
              0.0, surface(0.45F, 1.9F, id++));
    w.add_box({room_x1 + kThin, room_y, kHeight / 2}, {kThin, kRoomDepth / 2 + kThin, kHeight / 2},
              0.0, surface(0.45F, 1.9F, id++));
    w.add_box({(room_x0 + room_x1) / 2, y_far + kThin, kHeight / 2},
              {kRoomLength / 2 + 2 * kThin, kThin, kHeight / 2}, 0.0, surface(0.45F, 1.9F, id++));
    x = room_x1;
  }
  const double end = kStart + kLength + kWall;
  w.add_box({(x + end) / 2, y_wall, kHeight / 2}, {(end - x) / 2, kThin, kHeight / 2}, 0.0,
            surface(0.5F, 2.0F, id++));
  w.build();
  return w;
}

World make_street_world(std::uint64_t seed, double length, const WorldOptions& options) {
  World w;
  constexpr double kStart = -20.0;
  constexpr double kHalfRoad = 7.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double end = kStart + length;
  // Ground (road and pavements) as one wide slab.
  w.add_box({kStart + length / 2, 0, -0.2}, {length / 2 + 50, 60.0, 0.2}, 0.0,
            surface(0.25F, 1.0F, 21));
  // Buildings on both sides, with gaps and varied setbacks and heights.
  for (const double side : {-1.0, 1.0}) {
    double x = kStart - 10.0;
    std::uint32_t id = side > 0 ? 1000 : 2000;
    while (x < end + 10.0) {
      const double width = 8.0 + 17.0 * unit(rng);
      const double depth = 8.0 + 6.0 * unit(rng);
      const double height = 6.0 + 24.0 * unit(rng);
      const double setback = kHalfRoad + 3.0 + 4.0 * unit(rng);
      const double yaw = 0.06 * (unit(rng) - 0.5);
      w.add_box({x + width / 2, side * (setback + depth / 2), height / 2},
                {width / 2, depth / 2, height / 2}, yaw,
                surface(static_cast<float>(0.2 + 0.6 * unit(rng)), 0.8F, id++));
      x += width + (unit(rng) < 0.3 ? 3.0 + 6.0 * unit(rng) : 0.5);
    }
  }
  // Street poles every 25 m on both kerbs, and trees between them.
  std::uint32_t id = 5000;
  for (double x = kStart; x < end; x += 25.0) {
    for (const double side : {-1.0, 1.0}) {
      w.add_cylinder({x + 3.0 * unit(rng), side * (kHalfRoad + 0.5), 0.0}, 0.1, 6.0,
                     surface(0.8F, 6.0F, id++));
      const double tx = x + 12.5 + 2.0 * (unit(rng) - 0.5);
      const double ty = side * (kHalfRoad + 1.5);
      const double trunk = 2.0 + unit(rng);
      w.add_cylinder({tx, ty, 0.0}, 0.15, trunk, surface(0.4F, 5.0F, id++));
      Surface crown = surface(0.35F, 4.0F, id++);
      if (options.foliage) crown.foliage_free_path_m = kFoliageFreePathM;
      w.add_sphere({tx, ty, trunk + 1.2}, 1.3 + 0.5 * unit(rng), crown);
    }
  }
  if (options.foliage) {
    // Hedges along the building fronts: 0.8 m deep, 1-1.6 m tall, 4-14 m long. Their own random
    // stream, so the rest of the street is the same with and without them.
    std::mt19937_64 hedge_rng(seed ^ 0x68656467ULL);
    Surface leaves = surface(0.4F, 5.0F, 6000);
    leaves.foliage_free_path_m = 0.5F * kFoliageFreePathM;
    for (const double side : {-1.0, 1.0}) {
      for (double x = kStart + 5.0 * unit(hedge_rng); x < end;) {
        const double len = 4.0 + 10.0 * unit(hedge_rng);
        const double height = 1.0 + 0.6 * unit(hedge_rng);
        w.add_box({x + len / 2, side * (kHalfRoad + 2.6), height / 2}, {len / 2, 0.4, height / 2},
                  0.0, leaves);
        x += len + 6.0 + 20.0 * unit(hedge_rng);
      }
    }
  }
  w.build();
  return w;
}

}  // namespace livod::sim
