#pragma once
// Which recording each sensor replays. The configuration names recordings (source.replay); the
// command line may add or replace them:
//   NAME=PATH   sensor NAME replays PATH (a bag keeps the sensor's configured topic);
//   PATH        by format, from the extension: a .pcap/.pcapng goes to every packet LiDAR, a
//               .log/.candump to every CAN IMU, a .bag to every sensor configured with a rosbag1
//               replay (keeping their topics), a folder to the cameras. Two bare paths of one
//               format are ambiguous (use NAME=PATH).
// A sensor configured with a UDP source keeps its configured ports as the pcap port filter.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"

namespace livod::daemon::replay {

struct SensorRecording {
  ReplaySourceConfig replay;
  std::vector<std::uint16_t> ports;  // pcap port filter; empty = the decoder's default ports
  bool from_command_line = false;
};

// One entry per config.sensors[i]: its recording, or nullopt when it has none (a live source and
// no command-line input). Throws livod::Error for an unknown sensor name, a path that does not
// exist, an unknown extension, ambiguous bare paths or an input no sensor can take.
std::vector<std::optional<SensorRecording>> assign_recordings(
    const LivodConfig& config, const std::vector<std::string>& inputs);

}  // namespace livod::daemon::replay
