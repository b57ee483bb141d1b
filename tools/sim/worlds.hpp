#pragma once
// The simulator's named worlds. Each is deterministic for a seed.

#include <cstdint>

#include "tools/sim/world.hpp"

namespace livod::sim {

// Options of the named worlds (a scenario's `scene:`).
struct WorldOptions {
  // Vegetation scatters LiDAR beams in its volume instead of being a solid surface: tree crowns
  // (and, in the street, hedges; in the room, potted plants) get a mean free path. Without it
  // crowns are solid spheres and there are no hedges or plants.
  bool foliage = false;
};

// Beer-Lambert mean free path of a LiDAR beam in a crown: 1 / (G LAD) with the projection
// function G = 0.5 of randomly oriented leaves and a leaf area density of 2 m^2/m^3, the upper
// range of urban street trees.
inline constexpr float kFoliageFreePathM = 1.0F;

// An indoor room (12 x 9 x 3 m, origin at the floor centre) with furniture-scale boxes and two
// columns along the walls, leaving the centre (radius ~3 m) free for the trajectory.
World make_room_world(std::uint64_t seed, const WorldOptions& options = {});

// A long featureless corridor along +x (80 m x 2.4 m x 3 m, starting at x = -5): LiDAR
// geometry constrains everything but the translation along the axis.
World make_corridor_world();

// The same corridor with a 1 m doorway in its thin left wall (+y) every 6 m from x = 3, each
// into a 2.5 x 3 m room extending back (-x) from it: a LiDAR looking forward along the corridor
// sees faces with a normal along x only as slivers through the doorways at grazing angles; one
// looking sideways sees into the rooms, whose side walls constrain the translation along x.
World make_corridor_side_rooms_world();

// An outdoor street along +x of `length` metres (from x = -20): ground, buildings on both sides
// of a 14 m wide road, street poles every 25 m and trees (trunk + crown); with foliage, hedges in
// front of the buildings.
World make_street_world(std::uint64_t seed, double length, const WorldOptions& options = {});

}  // namespace livod::sim
