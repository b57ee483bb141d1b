#pragma once
// MD5 (RFC 1321). Only for ROS message type identity (the md5sum of a message definition), never
// for security.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace livod::io::rosbag {

std::array<std::uint8_t, 16> md5(std::string_view bytes);

// Lower-case hex, 32 characters (the form ROS uses).
std::string md5_hex(std::string_view bytes);

}  // namespace livod::io::rosbag
