// ROS 2 .msg text (the `ros2msg` schema encoding of MCAP and of rosbag2's message definitions)
// generated from the parsed IDL types, with every dependency appended as ROS 2 does.
#pragma once

#include <string>

#include "unav_introspection/type_registry.hpp"

namespace unav::bag {

/// The .msg text of `type_name` ("sensor_msgs/msg/Image" or a DDS name) followed by each nested
/// type it uses, in first-use order, each after a line of 80 '=' and "MSG: pkg/msg/Type".
/// Throws unav::introspection::UnknownTypeError / IdlError when a type has no IDL.
std::string ros2msg_definition(unav::introspection::TypeRegistry& registry, const std::string& type_name);

}  // namespace unav::bag
