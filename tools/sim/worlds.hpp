#pragma once
// The simulator's named worlds. Each is deterministic for a seed.

#include <cstdint>

#include "tools/sim/world.hpp"

namespace livod::sim {

// An indoor room (12 x 9 x 3 m, origin at the floor centre) with furniture-scale boxes and two
// columns along the walls, leaving the centre (radius ~3 m) free for the trajectory.
World make_room_world(std::uint64_t seed);

// A long featureless corridor along +x (80 m x 2.4 m x 3 m, starting at x = -5): LiDAR
// geometry constrains everything but the translation along the axis.
World make_corridor_world();

// The same corridor with a 1 m doorway in its thin left wall (+y) every 6 m from x = 3, each
// into a 2.5 x 3 m room extending back (-x) from it: a LiDAR looking forward along the corridor
// sees faces with a normal along x only as slivers through the doorways at grazing angles; one
// looking sideways sees into the rooms, whose side walls constrain the translation along x.
World make_corridor_side_rooms_world();

// An outdoor street along +x of `length` metres (from x = -20): ground, buildings on both sides
// of a 14 m wide road, street poles every 25 m and trees (trunk + crown).
World make_street_world(std::uint64_t seed, double length);

}  // namespace livod::sim
