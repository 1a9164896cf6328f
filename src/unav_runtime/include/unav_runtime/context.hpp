// The process-wide runtime: one DomainParticipant, one executor, one clock, the command-line
// ROS arguments, signal handling and the ros_discovery_info graph that `ros2 node list` and
// `unav node list` read.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "unav_runtime/clock.hpp"
#include "unav_runtime/executor.hpp"
#include "unav_runtime/qos.hpp"
#include "unav_runtime/ros_args.hpp"
#include "unav_runtime/security.hpp"

namespace eprosima::fastdds::dds {
class DomainParticipant;
class Publisher;
class Subscriber;
class Topic;
class TopicDataType;
class DataWriter;
class DataReader;
class DataWriterQos;
class DataReaderQos;
class DomainParticipantListener;
}  // namespace eprosima::fastdds::dds

namespace unav {

class Node;
class BoundSwitch;

struct ContextOptions {
  /// DDS domain; -1 reads ROS_DOMAIN_ID (default 0).
  int domain_id = -1;
  /// Block SIGINT/SIGTERM and turn them into shutdown() (the first) and _exit(130) (another one
  /// more than 2 s later, when a clean shutdown hangs).
  bool handle_signals = true;
  /// With UNAV_TRANSPORT=shm (see shm_transport_from_environment): the shared-memory segment per
  /// participant, larger than the biggest sample (a 640x480 rgb8 image is 0.9 MB).
  uint32_t shm_segment_bytes = 32u * 1024u * 1024u;
  /// Data-sharing delivery for endpoints whose QoS asks for it (QoS::data_sharing);
  /// UNAV_DATA_SHARING=off turns it off for the process.
  bool data_sharing = true;
  /// Participant name shown by DDS tools; defaults to argv[0]'s base name.
  std::string participant_name;
  /// DDS Security switches; unset: read ROS_SECURITY_* from the environment (security.hpp).
  /// The enclave is ROS_SECURITY_ENCLAVE_OVERRIDE, else `--ros-args --enclave`, else `enclave`
  /// below, else "/".
  std::optional<security::Environment> security;
  std::string enclave;
  /// Attached at creation so no discovery event is missed (tools listing the graph).
  eprosima::fastdds::dds::DomainParticipantListener* participant_listener = nullptr;
};

/// The transports a participant uses, from UNAV_TRANSPORT: unset, "" or "udp": UDPv4 only (the
/// default; same-host images still go by data-sharing); "shm": Fast DDS' shared-memory transport
/// too (lower latency for large samples outside data-sharing, but Fast DDS 2.9 loses a peer that
/// restarts after another process on the host was SIGKILLed: context.cpp). Anything else is a
/// ConfigError naming the variable, its value and the choices.
bool shm_transport_from_environment();

class Context {
 public:
  Context(int argc, const char* const* argv, const ContextOptions& options = {});
  explicit Context(const ContextOptions& options = {}) : Context(0, nullptr, options) {}
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const RosArgs& args() const { return args_; }
  int domain_id() const { return domain_id_; }
  /// The security enclave this participant authenticated as; empty when security is off.
  const std::string& secured_enclave() const { return secured_enclave_; }
  Executor& executor() { return executor_; }
  Clock& clock() { return clock_; }

  bool ok() const { return !executor_.is_shutdown(); }
  void shutdown() { executor_.shutdown(); }
  void spin() { executor_.spin(); }
  bool spin_until(const std::function<bool()>& done, std::chrono::nanoseconds timeout) {
    return executor_.spin_until(done, timeout);
  }
  void spin_some(std::chrono::nanoseconds max_wait = std::chrono::nanoseconds(0)) { executor_.spin_some(max_wait); }
  /// Registers a callback run (on the calling thread of shutdown handling) before exit, e.g. to
  /// flush files. Runs in reverse order of registration from ~Context.
  void on_shutdown(std::function<void()> fn) { shutdown_hooks_.push_back(std::move(fn)); }

  // --- used by Node, Publisher and Subscription ---
  eprosima::fastdds::dds::DomainParticipant* participant() { return participant_; }
  eprosima::fastdds::dds::Topic* topic(const std::string& dds_topic, eprosima::fastdds::dds::TopicDataType* type);
  eprosima::fastdds::dds::DataWriter* create_writer(eprosima::fastdds::dds::Topic* topic, const QoS& qos);
  eprosima::fastdds::dds::DataReader* create_reader(eprosima::fastdds::dds::Topic* topic, const QoS& qos,
                                                    void* listener);
  void delete_writer(eprosima::fastdds::dds::DataWriter* w);
  /// Puts `fresh` in `slot` under the graph's lock (publish_graph() reads the publishers' writers
  /// from any thread) and deletes the writer it held after that, outside the lock.
  void replace_writer(eprosima::fastdds::dds::DataWriter*& slot, eprosima::fastdds::dds::DataWriter* fresh);
  void delete_reader(eprosima::fastdds::dds::DataReader* r);
  void add_node(Node* node);
  void remove_node(Node* node);
  /// Publishes the node/entity graph on ros_discovery_info (called when entities change).
  void publish_graph();
  /// Subscribes /clock once and switches the clock to simulated time.
  void enable_sim_time();

 private:
  void signal_loop();
  void stop_signal_thread();
  void clean_dead_data_sharing();
  void create_participant(int argc, const char* const* argv, const ContextOptions& options, const std::string& enclave,
                          const std::optional<std::vector<std::pair<std::string, std::string>>>& security_properties,
                          const std::string& security_warning, const std::string& keystore);
  std::string access_hint(const char* way) const;
  /// The topic's type as a BoundSwitch when data-sharing applies to `q`; nullptr otherwise.
  BoundSwitch* data_sharing_type(eprosima::fastdds::dds::Topic* topic, const QoS& q, bool writer);

  RosArgs args_;
  int domain_id_ = 0;
  std::string secured_enclave_;
  Clock clock_;
  Executor executor_{clock_};
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::mutex mutex_;
  std::mutex endpoint_mutex_;  // a type's bound is set for one endpoint creation at a time
  bool data_sharing_ = true;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  std::vector<std::unique_ptr<eprosima::fastdds::dds::TopicDataType>> owned_types_;
  std::vector<Node*> nodes_;
  eprosima::fastdds::dds::DataWriter* graph_writer_ = nullptr;
  std::shared_ptr<void> clock_subscription_;
  std::vector<std::function<void()>> shutdown_hooks_;
  bool handle_signals_ = false;
  std::thread signal_thread_;
  std::atomic<bool> exiting_{false};
};

}  // namespace unav
