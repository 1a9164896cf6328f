// What DDS discovery tells about the ROS graph: topics with their types and QoS, and nodes
// (from ros_discovery_info, as `ros2 node list` reads them).
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "unav_runtime/runtime.hpp"

namespace unav::cli {

struct EndpointInfo {
  std::string dds_topic;
  std::string dds_type;
  bool is_writer = false;
  bool reliable = false;
  bool transient_local = false;
  std::string participant_key;  ///< 12-byte GUID prefix of the owning participant
};

/// A DDS participant (with its own context) that watches discovery.
class Graph {
 public:
  Graph();
  ~Graph();
  unav::Context& context() { return *ctx_; }
  /// Endpoints discovered so far (remote ones: other processes, any vendor).
  std::vector<EndpointInfo> endpoints() const;
  /// topic (ROS name) -> set of DDS type names, for topics under rt/.
  std::map<std::string, std::set<std::string>> topics() const;
  /// The DDS type name of a writer of `topic` discovered so far, or "" (none yet).
  std::string writer_type(const std::string& ros_topic) const;
  /// Waits until `topic` has a writer; returns its DDS type name or "" on timeout.
  std::string wait_for_type(const std::string& ros_topic, std::chrono::milliseconds timeout);
  /// QoS that matches every current writer of `topic` (best effort if any is best effort;
  /// transient local only if all are), as `ros2 topic echo` chooses.
  unav::QoS matching_qos(const std::string& ros_topic) const;
  /// Fully qualified node names announced on ros_discovery_info.
  std::vector<std::string> nodes();

 private:
  struct Listener;
  std::unique_ptr<Listener> listener_;
  std::unique_ptr<unav::Context> ctx_;
};

/// Milliseconds to wait for discovery: UNAV_SPIN_TIME (seconds) or 2 s.
std::chrono::milliseconds default_spin_time();

}  // namespace unav::cli
