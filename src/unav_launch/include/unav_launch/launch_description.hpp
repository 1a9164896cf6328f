// YAML launch files (the ROS 2 YAML launch format, plus `required`), loaded and validated.
//
//   launch:
//     - arg: {name: rate, default: "10.0", description: "publish rate [Hz]"}
//     - node: {pkg: unav_examples, exec: talker, name: talker, namespace: rov,
//              param: [{from: FILE}, {name: rate, value: "$(var rate)"}],
//              remap: [{from: chatter, to: /rov/chatter}], args: "--extra flag",
//              ros_args: "--enclave /rov/talker",
//              env: [{name: FOO, value: bar}], respawn: true, respawn_delay: 1.0,
//              required: true, output: screen}     # `on_exit: shutdown` == `required: true`
//     - include: {file: "$(dirname)/other.launch.yaml", arg: [{name: rate, value: "5"}]}
//
// Substitutions in any string value: $(var NAME), $(env VAR), $(env VAR DEFAULT),
// $(find-pkg-share PKG), $(find-pkg-prefix PKG), $(dirname); they nest. An include's relative
// `file` is relative to the including file; a relative param `from` to the working directory.
// An included file sees the arguments of its parent, overridden by the include's `arg` list;
// its own declarations do not leak back.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace unav::launch {

/// A launch file (or the command line) is invalid. what() is one line naming the file, the
/// entry and the broken rule, e.g. "a.launch.yaml:7: launch[2].node (pkg 'p', exec 'e'):
/// executable 'e' not found in package 'p' (searched: /ws/install/p/lib/p)".
class LaunchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One `param` entry of a node, in file order.
struct NodeParameter {
  std::string file;  ///< Parameters file (existing), passed as --params-file FILE; or empty.
  std::string name;  ///< When file is empty: passed as -p NAME:=VALUE.
  std::string value;
};

/// A node to start, with every substitution resolved and every path checked.
struct NodeDescription {
  std::string package;
  std::string executable;             ///< Executable name as in the file.
  std::string executable_path;        ///< Resolved file, <prefix>/lib/<package>/<executable>.
  std::string name;                   ///< Node name remap (-r __node:=); empty keeps the node's own.
  std::string ns;                     ///< Absolute namespace ("/rov"), empty for none.
  std::vector<std::string> args;      ///< Extra argv before --ros-args.
  std::vector<std::string> ros_args;  ///< Extra ROS arguments after --ros-args (`--enclave /e`).
  std::vector<NodeParameter> parameters;
  std::vector<std::pair<std::string, std::string>> remaps;  ///< from, to
  std::vector<std::pair<std::string, std::string>> env;     ///< name, value (added/overridden)
  bool respawn = false;
  double respawn_delay_s = 0.0;   ///< Wait before a respawn [s].
  bool required = false;          ///< Its exit shuts the whole launch down.
  std::string output = "screen";  ///< "screen", "log" or "both"; all output goes to the
                                  ///< supervisor's stream (no log files).
  std::string source;             ///< Where it was declared: "file:line launch[i].node".
};

/// A resolved launch argument.
struct LaunchArgument {
  std::string name;
  std::string value;
  std::string description;
  std::string file;  ///< Launch file that declared it.
};

/// Everything a launch file (with its includes) starts, in start order.
struct LaunchDescription {
  std::string file;
  std::vector<LaunchArgument> arguments;  ///< In declaration order, includes inline.
  std::vector<NodeDescription> nodes;
};

/// Loads and validates `path` and the files it includes. `arg_overrides` (from NAME:=VALUE on
/// the command line) win over declared defaults everywhere; each must name an argument some
/// loaded file declares. Throws LaunchError on any invalid input; nothing is started.
LaunchDescription load_launch_file(const std::string& path,
                                   const std::map<std::string, std::string>& arg_overrides = {});

/// Parses command-line launch arguments "NAME:=VALUE". Throws LaunchError on other shapes.
std::map<std::string, std::string> parse_launch_arguments(const std::vector<std::string>& items);

/// The node's argv: [executable_path, args..., --ros-args, -r, __node:=NAME, -r, __ns:=/NS,
/// (--params-file F | -p k:=v)..., (-r from:=to)..., ros_args...]; no --ros-args when there is nothing
/// to pass after it.
std::vector<std::string> node_argv(const NodeDescription& node);

}  // namespace unav::launch
