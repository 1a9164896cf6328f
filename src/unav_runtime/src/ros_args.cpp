#include "unav_runtime/ros_args.hpp"

#include "unav_runtime/errors.hpp"

namespace unav {
namespace {

// Splits "[node:]from:=to" (node prefix only when the part before ":=" has a single ':' that is
// not part of "::").
void split_rule(const std::string& arg, const std::string& flag, std::string& node, std::string& from,
                std::string& to) {
  const size_t sep = arg.find(":=");
  if (sep == std::string::npos || sep == 0)
    throw ArgumentError("argument '" + flag + " " + arg + "': expected 'name:=value'");
  std::string lhs = arg.substr(0, sep);
  to = arg.substr(sep + 2);
  const size_t colon = lhs.find(':');
  if (colon != std::string::npos) {
    node = lhs.substr(0, colon);
    lhs = lhs.substr(colon + 1);
  }
  from = lhs;
  if (from.empty()) throw ArgumentError("argument '" + flag + " " + arg + "': empty name before ':='");
}

}  // namespace

RosArgs parse_ros_args(const std::vector<std::string>& argv) {
  RosArgs out;
  bool in_ros = false;
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a == "--ros-args") {
      in_ros = true;
      continue;
    }
    if (!in_ros) {
      out.non_ros_args.push_back(a);
      continue;
    }
    if (a == "--") {
      in_ros = false;
      continue;
    }
    auto value = [&](const char* what) -> const std::string& {
      if (i + 1 >= argv.size()) throw ArgumentError("argument '" + a + "' expects " + what);
      return argv[++i];
    };
    if (a == "-p" || a == "--param") {
      ParamOverride p;
      split_rule(value("name:=value"), a, p.node, p.name, p.value);
      out.params.push_back(p);
    } else if (a == "-r" || a == "--remap") {
      RemapRule r;
      split_rule(value("from:=to"), a, r.node, r.from, r.to);
      if (r.from == "__node" || r.from == "__name")
        out.node_name = r.to;
      else if (r.from == "__ns")
        out.node_namespace = r.to;
      else
        out.remaps.push_back(r);
    } else if (a == "-e" || a == "--enclave") {
      out.enclave = value("an enclave name (/rov/physics_server)");
    } else if (a == "--params-file") {
      out.params_files.push_back(value("a file path"));
    } else if (a == "--log-level") {
      std::string level = value("a level (debug, info, warn, error, fatal)");
      const size_t sep = level.find(":=");
      if (sep != std::string::npos) level = level.substr(sep + 2);  // per-logger levels: global here
      for (const char* ok : {"debug", "info", "warn", "error", "fatal", "DEBUG", "INFO", "WARN", "ERROR", "FATAL"})
        if (level == ok) out.log_level = level;
      if (out.log_level.empty())
        throw ArgumentError("argument '--log-level " + level + "': expected debug, info, warn, error or fatal");
    } else if (a == "--enable-rosout-logs" || a == "--disable-rosout-logs" || a == "--enable-stdout-logs" ||
               a == "--disable-stdout-logs" || a == "--enable-external-lib-logs" ||
               a == "--disable-external-lib-logs") {
      // accepted for compatibility with ros2 launch; no effect
    } else {
      throw ArgumentError("unknown ROS argument '" + a +
                          "' (known: -p/--param, -r/--remap, --params-file, --log-level, -e/--enclave)");
    }
  }
  return out;
}

RosArgs parse_ros_args(int argc, const char* const* argv) {
  return parse_ros_args(std::vector<std::string>(argv, argv + argc));
}

}  // namespace unav
