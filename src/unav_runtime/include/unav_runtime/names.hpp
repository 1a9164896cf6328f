// ROS 2 name resolution: node names, namespaces, topic names, remapping and the DDS topic prefix.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace unav {

/// A remap rule `from:=to` as given with `-r`. `node` is empty for rules that apply to every node,
/// or the node name for a `node:from:=to` rule.
struct RemapRule {
  std::string node;
  std::string from;
  std::string to;
};

/// Throws NameError when `name` is not a valid ROS 2 node name ([A-Za-z_][A-Za-z0-9_]*).
void validate_node_name(const std::string& name);
/// Normalises a namespace to "/a/b" form ("" and "/" give "/"); throws NameError when invalid.
std::string normalize_namespace(const std::string& ns);
/// Resolves a topic name as ROS 2 does: absolute "/x" stays, "x" becomes "<ns>/x", "~/x" becomes
/// "<ns>/<node>/x". Throws NameError for invalid characters, "//", a trailing "/", or "~" misuse.
std::string resolve_topic_name(const std::string& name, const std::string& node_namespace,
                               const std::string& node_name);
/// Applies the first matching remap rule (rules are resolved like topic names before matching).
std::string apply_remaps(const std::string& resolved, const std::vector<RemapRule>& rules,
                         const std::string& node_namespace, const std::string& node_name);
/// "/rov/imu" -> "rt/rov/imu" (the rmw_fastrtps topic prefix).
std::string to_dds_topic(const std::string& ros_topic);
/// "rt/rov/imu" -> "/rov/imu"; names without a ROS prefix are returned unchanged.
std::string from_dds_topic(const std::string& dds_topic);
/// "sensor_msgs::msg::dds_::Image_" -> "sensor_msgs/msg/Image"; other names unchanged.
std::string ros_type_from_dds(const std::string& dds_type);
/// "sensor_msgs/msg/Image" or "sensor_msgs/Image" -> "sensor_msgs::msg::dds_::Image_".
std::string dds_type_from_ros(const std::string& ros_type);

}  // namespace unav
