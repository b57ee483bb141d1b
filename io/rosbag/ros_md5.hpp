#pragma once
// The ROS1 md5sum of a message type, computed from its full message_definition text (the message
// followed by every dependency after a line of 80 '=' and "MSG: <type>", as bag connection
// records carry it). Follows genmsg's compute_md5_text: comments and blank lines dropped,
// constants first as "type NAME=value", then fields as "type name" for built-in types (array
// suffix kept) or "<md5 of the field's type> name" for message types (array suffix dropped),
// joined by '\n'. "Header" means std_msgs/Header; a bare type name means the same package.

#include <string>
#include <string_view>

namespace livod::io::rosbag {

// `type` is the full name of the top-level message ("sensor_msgs/Imu"). Throws livod::Error when
// the text is malformed or names a type it does not define.
std::string compute_ros_md5sum(std::string_view type, std::string_view full_definition);

}  // namespace livod::io::rosbag
