// Parameters from ROS 2-style YAML files (`node: {ros__parameters: {...}}`, `/**:` wildcards,
// nested maps flattened to dotted names) and `-p` overrides; Node::declare_params() applies them
// to a config schema (unav_common/config.hpp), which types and checks every value.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_runtime/ros_args.hpp"

namespace unav {

/// One value given for a parameter, and where it came from (for error messages).
struct ParameterOverride {
  YAML::Node value;
  std::string source;  ///< "params file 'cfg/x.yaml'" or "command line '-p rate:=2'"
};

/// All override values that apply to one node, merged: later files win, `-p` wins over files.
class ParameterOverrides {
 public:
  ParameterOverrides() = default;
  /// Reads every params file of `args` and keeps the entries matching the node's fully
  /// qualified name. Throws ParameterError naming the file (missing, malformed, wrong layout).
  ParameterOverrides(const RosArgs& args, const std::string& node_namespace, const std::string& node_name);

  const ParameterOverride* find(const std::string& name) const;
  void mark_used(const std::string& name) { used_.push_back(name); }
  /// Override names that no declare_params() asked for.
  std::vector<std::string> unused() const;
  const std::map<std::string, ParameterOverride>& all() const { return values_; }

 private:
  std::map<std::string, ParameterOverride> values_;
  std::vector<std::string> used_;
};

}  // namespace unav
