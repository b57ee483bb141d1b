#pragma once
// A short human-readable description of a loaded configuration: what `livod check-config`
// prints on success and what `livod run` logs at start.

#include <string>

#include "daemon/config/config.hpp"

namespace livod::daemon {

// One line for the body frame, one per sensor, one for the outputs; ends with a newline.
std::string summarize_config(const LivodConfig& config);

}  // namespace livod::daemon
