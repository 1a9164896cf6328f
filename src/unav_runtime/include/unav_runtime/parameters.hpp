// Parameters from ROS 2-style YAML files (`node: {ros__parameters: {...}}`, `/**:` wildcards,
// nested maps flattened to dotted names) and `-p` overrides, with typed, validated access.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_runtime/ros_args.hpp"

namespace unav {

struct ParameterDescriptor {
  std::string description;  ///< one line, with the unit
  std::optional<double> min;  ///< inclusive lower bound for numbers
  std::optional<double> max;  ///< inclusive upper bound for numbers
  bool allow_non_finite = false;  ///< NaN/Inf are rejected unless this is set
};

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
  /// Override names that no declare_parameter() asked for.
  std::vector<std::string> unused() const;
  const std::map<std::string, ParameterOverride>& all() const { return values_; }

 private:
  std::map<std::string, ParameterOverride> values_;
  std::vector<std::string> used_;
};

/// Converts a YAML value to T (bool, int, int64_t, double, std::string, or std::vector of those),
/// checking the descriptor. Throws ParameterError "<context>: expected <type>, got '<value>'".
template <typename T>
T parameter_as(const YAML::Node& value, const ParameterDescriptor& desc, const std::string& context);

/// Type name used in messages ("double", "integer", "string array", ...).
template <typename T>
const char* parameter_type_name();

}  // namespace unav
