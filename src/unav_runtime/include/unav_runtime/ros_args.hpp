// Command-line arguments in ROS 2 form: `--ros-args --params-file F -p name:=value -r from:=to
// -r __node:=name -r __ns:=/ns --log-level debug -e /enclave [--]`.
#pragma once

#include <string>
#include <vector>

#include "unav_runtime/names.hpp"

namespace unav {

struct ParamOverride {
  std::string node;   ///< empty: every node; else `node:name:=value`
  std::string name;   ///< dotted parameter name
  std::string value;  ///< YAML text of the value
};

struct RosArgs {
  std::vector<std::string> params_files;
  std::vector<ParamOverride> params;
  std::vector<RemapRule> remaps;
  std::string node_name;                  ///< from `-r __node:=name`, empty if absent
  std::string node_namespace;             ///< from `-r __ns:=/ns`, empty if absent
  std::string log_level;                  ///< from `--log-level`, empty if absent
  std::string enclave;                    ///< from `-e/--enclave` (DDS Security), empty if absent
  std::vector<std::string> non_ros_args;  ///< everything outside --ros-args (argv[0] first)
};

/// Parses argv. Throws ArgumentError naming the offending argument for unknown flags inside
/// --ros-args, a missing value, or a rule without ":=".
RosArgs parse_ros_args(const std::vector<std::string>& argv);
RosArgs parse_ros_args(int argc, const char* const* argv);

}  // namespace unav
