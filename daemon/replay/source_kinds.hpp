#pragma once
// The concrete replay sources behind make_source() (sources.hpp); one file per recording format.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/replay/sources.hpp"
#include "drivers/lidar_decoder.hpp"
#include "drivers/ouster/metadata.hpp"

namespace livod::daemon::replay {

// UDP datagrams of a pcap/pcapng capture, kept when their destination port is in `ports` (empty:
// the decoder's default ports), through a packet decoder.
std::unique_ptr<ReplaySource> make_pcap_source(const std::filesystem::path& file,
                                               std::unique_ptr<drivers::LidarDecoder> decoder,
                                               const std::vector<std::uint16_t>& ports);

// CAN frames of a candump log through the configured CAN IMU decoder (SBG, Bosch MM7, custom).
std::unique_ptr<ReplaySource> make_candump_source(const std::filesystem::path& file,
                                                  const CanConfig& can, const std::string& sensor);

// One topic of a ROS1 bag. The message type decides: sensor_msgs/Imu -> IMU samples;
// sensor_msgs/PointCloud2, livox_ros_driver/CustomMsg -> scans; ouster_ros/PacketMsg -> the
// packet decoder (`decoder` must then be given).
// The Ouster metadata an ouster_ros bag carries: the std_msgs/String topic "metadata" beside the
// packet topic (/os_node/lidar_packets -> /os_node/metadata), else the bag's only String topic
// named "*metadata". Throws livod::Error naming the bag when it has none or it does not parse.
drivers::ouster::SensorMetadata bag_ouster_metadata(const std::filesystem::path& file,
                                                    const std::string& packet_topic);

std::unique_ptr<ReplaySource> make_bag_source(const std::filesystem::path& file,
                                              const std::string& topic, const SensorConfig& sensor,
                                              std::unique_ptr<drivers::LidarDecoder> decoder);

}  // namespace livod::daemon::replay
