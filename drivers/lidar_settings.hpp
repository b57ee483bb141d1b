#pragma once
// The families' own configuration options, one struct per family that has any (the struct lives
// with its family), gathered in one variant for the family-neutral code that carries them.

#include <variant>

#include "drivers/hesai/settings.hpp"
#include "drivers/velodyne/settings.hpp"

namespace livod::drivers {

using LidarSettings =
    std::variant<std::monostate, velodyne::VelodyneSettings, hesai::HesaiSettings>;

}  // namespace livod::drivers
