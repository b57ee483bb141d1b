#pragma once
// Recorded streams for replay. A source reads one sensor's recording one event at a time (a UDP
// datagram of a pcap, a frame of a candump log, a message of a ROS1 bag), tells the receive time
// of its next event (pcap record time, candump log time, bag record time: the host clock of the
// recording) and, when the replay's merge picks it, decodes that event into scans and IMU
// samples with their sensor and host stamps (`mapped` is left to the clock domain).
//
// Memory is bounded by construction: a source holds at most one undecoded event and its decoder's
// scan under construction; files are streamed, never loaded whole.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/runtime/source.hpp"
#include "drivers/lidar_decoder.hpp"
#include "io/input_loss.hpp"

namespace livod::daemon::replay {

// Recorded streams implement the runtime's source interface (daemon/runtime/source.hpp).
using ReplaySource = runtime::MeasurementSource;

// The source for one sensor's recording. `ports`: the UDP destination ports to keep from a pcap
// (empty: the decoder's defaults). Throws livod::Error naming the sensor when the recording
// cannot be opened or when this driver cannot be replayed from this format (e.g. a custom CAN
// decoder, a bag topic of an unexpected message type).
std::unique_ptr<ReplaySource> make_source(const SensorConfig& sensor,
                                          const ReplaySourceConfig& replay,
                                          const std::vector<std::uint16_t>& ports);

}  // namespace livod::daemon::replay
