#pragma once
// A scenario without the simulator's realism, as `livod sim --plain` simulates it.

#include "tools/sim/scenario.hpp"

namespace livod::sim {

// Every LiDAR's plain range model (plain_range_model) and no moving objects or foliage.
void make_plain(Scenario& scenario);

}  // namespace livod::sim
