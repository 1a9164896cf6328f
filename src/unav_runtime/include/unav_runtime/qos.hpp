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
  /// Fast DDS data-sharing between processes on one host: a writer serialises each sample once
  /// into a shared-memory pool that the readers on the host deserialise from in place (no
  /// transport copy; ~0.4 ms instead of ~0.75 ms for a 640x480 rgb8 image). Wire format and type
  /// name are unchanged: ROS 2, Cyclone and remote readers are served by the transports as before.
  /// Writers must give `max_sample_bytes`, the largest CDR size they will write
  /// (unav::serialized_bytes(prototype)); a larger sample is refused with an error naming the
  /// topic. Readers opt in with max_sample_bytes = 0 (they accept any size). Off under DDS
  /// Security, with UNAV_DATA_SHARING=off, or for endpoints that do not ask for it.
  bool data_sharing = false;
  uint32_t max_sample_bytes = 0;

  /// Best effort, keep last 5: cameras, IMU, anything where the newest sample matters.
  static QoS sensor_data() { return {Reliability::kBestEffort, Durability::kVolatile, 5}; }
  /// Reliable, keep last 10 (ROS 2's default).
  static QoS reliable(int32_t depth = 10) { return {Reliability::kReliable, Durability::kVolatile, depth}; }
  /// Reliable, transient local, keep last 1: camera_info, world descriptions; late joiners get it.
  static QoS static_latched() { return {Reliability::kReliable, Durability::kTransientLocal, 1}; }
  /// This profile with data-sharing delivery (see `data_sharing`).
  QoS with_data_sharing(uint32_t max_bytes = 0) const {
    QoS q = *this;
    q.data_sharing = true;
    q.max_sample_bytes = max_bytes;
    return q;
  }
  /// Profile by name: "sensor_data", "default", "static". Throws ConfigError otherwise.
  static QoS from_name(const std::string& name);
};

}  // namespace unav
