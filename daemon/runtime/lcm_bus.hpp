#pragma once
// The daemon's message bus on LCM: the publisher thread's calls forwarded to a
// publish::LcmPublisher (docs/lcm.md). Built only when outputs.lcm is enabled.

#include <memory>

#include "daemon/config/config.hpp"
#include "daemon/runtime/publisher.hpp"

namespace livod::daemon::runtime {

// Opens LCM on the configured URL (livod::Error naming it when LCM cannot start). `body_frame`
// names the body frame in every pose.
std::unique_ptr<MessageBus> make_lcm_bus(const LcmOutputConfig& config,
                                         const std::string& body_frame);

}  // namespace livod::daemon::runtime
