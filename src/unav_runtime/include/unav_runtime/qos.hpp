// QoS profiles named like ROS 2's (rmw_qos_profile_sensor_data, default, and a latched "static").
#pragma once

#include <cstdint>
#include <string>

namespace unav {

struct QoS {
  enum class Reliability { kReliable, kBestEffort };
  enum class Durability { kVolatile, kTransientLocal };
  Reliability reliability = Reliability::kReliable;
  Durability durability = Durability::kVolatile;
  int32_t depth = 10;  ///< history: keep last `depth`

  /// Best effort, keep last 5: cameras, IMU, anything where the newest sample matters.
  static QoS sensor_data() { return {Reliability::kBestEffort, Durability::kVolatile, 5}; }
  /// Reliable, keep last 10 (ROS 2's default).
  static QoS reliable(int32_t depth = 10) { return {Reliability::kReliable, Durability::kVolatile, depth}; }
  /// Reliable, transient local, keep last 1: camera_info, world descriptions; late joiners get it.
  static QoS static_latched() { return {Reliability::kReliable, Durability::kTransientLocal, 1}; }
  /// Profile by name: "sensor_data", "default", "static". Throws ConfigError otherwise.
  static QoS from_name(const std::string& name);
};

}  // namespace unav
