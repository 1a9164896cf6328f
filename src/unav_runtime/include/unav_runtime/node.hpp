// Node: a named participant of the ROS graph. Components derive from it and declare their ports
// (publishers, subscriptions, timers) and parameters in the constructor.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_runtime/context.hpp"
#include "unav_runtime/errors.hpp"
#include "unav_runtime/logging.hpp"
#include "unav_runtime/parameters.hpp"
#include "unav_runtime/publisher.hpp"

namespace unav {

struct NodeOptions {
  Context* context = nullptr;
};

class Node {
 public:
  /// `default_name`/`default_namespace` may be overridden with `-r __node:=` / `-r __ns:=`.
  /// Throws NameError/ParameterError for a bad name or unreadable params files.
  Node(const std::string& default_name, const NodeOptions& options, const std::string& default_namespace = "");
  virtual ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const { return name_; }
  const std::string& get_namespace() const { return namespace_; }
  std::string fully_qualified_name() const;
  const Logger& logger() const { return logger_; }
  Context& context() { return ctx_; }
  Time now() const { return ctx_.clock().now(); }

  /// Resolves a topic name relative to this node and applies the command-line remaps.
  std::string resolve_topic(const std::string& name) const;

  template <typename Msg>
  std::shared_ptr<Publisher<Msg>> create_publisher(const std::string& topic, const QoS& qos) {
    auto pub = std::make_shared<Publisher<Msg>>(ctx_, to_dds_topic(resolve_topic(topic)), qos);
    publishers_.push_back(pub);
    ctx_.publish_graph();
    return pub;
  }

  template <typename Msg>
  std::shared_ptr<Subscription<Msg>> create_subscription(const std::string& topic, const QoS& qos,
                                                         std::function<void(const Msg&)> callback) {
    auto sub = std::make_shared<Subscription<Msg>>(ctx_, to_dds_topic(resolve_topic(topic)), qos, std::move(callback));
    sub->start(qos);
    subscriptions_.push_back(sub);
    ctx_.publish_graph();
    return sub;
  }

  /// Steady-clock timer.
  std::shared_ptr<Timer> create_wall_timer(std::chrono::nanoseconds period, std::function<void()> callback);
  /// Timer on the node clock: follows simulated time when use_sim_time is true.
  std::shared_ptr<Timer> create_timer(std::chrono::nanoseconds period, std::function<void()> callback);

  /// Declares every field of a config schema (unav_common/config.hpp: a struct whose
  /// Serialize() names each field once with type, default, range, unit, doc) as parameters of
  /// this node: a params file or `-p name:=value` overrides a field (nested fields as `a.b`),
  /// checked by the schema's rules (errors name the source, key, value and rule). The fields
  /// are listed by `<node> --help`.
  template <class T>
  void declare_params(T* config);
  /// One row per declared parameter, in declaration order (what `--help` prints).
  const std::vector<common::FieldInfo>& parameter_table() const { return table_; }
  /// Value of a declared parameter as YAML (for tools and logs).
  const std::map<std::string, YAML::Node>& parameters() const { return values_; }
  /// Throws ParameterError listing overrides no declare_params() asked for (typos in YAML).
  void check_undeclared_parameters() const;

  // Graph introspection for ros_discovery_info.
  std::vector<const PublisherBase*> publishers() const;
  std::vector<const SubscriptionBase*> subscriptions() const;

 private:
  Context& ctx_;
  std::string name_;
  std::string namespace_;
  Logger logger_;
  ParameterOverrides overrides_;
  std::map<std::string, YAML::Node> values_;
  std::vector<common::FieldInfo> table_;
  void record_params(const std::vector<common::FieldInfo>& fields, const YAML::Node& effective);
  std::vector<std::shared_ptr<PublisherBase>> publishers_;
  std::vector<std::shared_ptr<SubscriptionBase>> subscriptions_;
};

template <class T>
void Node::declare_params(T* config) {
  const std::vector<common::FieldInfo> fields = common::Describe(*config);
  for (const auto& f : fields) {
    if (f.type == "mapping" || f.type == "mapping[]") continue;  // overrides name leaves
    if (const ParameterOverride* o = overrides_.find(f.name)) {
      overrides_.mark_used(f.name);
      // `-p name:=` (nothing after :=) is the empty string for a string parameter, as in ROS 2.
      const std::string text = o->value.IsNull() && f.type == "string" ? "\"\"" : YAML::Dump(o->value);
      common::ApplyOverride(config, f.name, text, o->source + ": node '" + name_ + "'");
    }
  }
  record_params(fields, common::ToYaml(*config));
}

/// Runs one component as a process: parses arguments, constructs NodeT, spins until SIGINT or
/// SIGTERM, destroys the node (flushing its outputs) and returns the exit code. Configuration
/// errors print one line "<exe>: error: <message>" and return 2.
template <typename NodeT>
int run_node(int argc, char** argv);

int run_node_impl(int argc, char** argv, const std::function<std::unique_ptr<Node>(const NodeOptions&)>& make);

template <typename NodeT>
int run_node(int argc, char** argv) {
  return run_node_impl(argc, argv, [](const NodeOptions& o) { return std::make_unique<NodeT>(o); });
}

}  // namespace unav
