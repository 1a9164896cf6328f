#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>
#include <sstream>

#include "unav_launch/launch_description.hpp"
#include "unav_launch/package_index.hpp"

namespace fs = std::filesystem;

namespace unav::launch {
namespace {

constexpr int kMaxIncludeDepth = 32;

// A broken rule inside one entry; the entry loop adds file, line and entry.
class RuleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (const auto& item : items) {
    out += (out.empty() ? "" : separator) + item;
  }
  return out;
}

std::vector<std::string> split_whitespace(const std::string& text) {
  std::istringstream stream(text);
  std::vector<std::string> out;
  for (std::string item; stream >> item;) {
    out.push_back(item);
  }
  return out;
}

std::string type_name(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "null";
    case YAML::NodeType::Scalar:
      return "a scalar '" + node.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a sequence";
    case YAML::NodeType::Map:
      return "a map";
    default:
      return "undefined";
  }
}

bool is_identifier(const std::string& text) {
  if (text.empty() || std::isdigit(static_cast<unsigned char>(text[0]))) {
    return false;
  }
  return std::all_of(text.begin(), text.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

// "rov/", "/rov" -> "/rov"; "" or "/" -> "".
std::string normalize_namespace(const std::string& ns) {
  std::string out;
  std::stringstream stream(ns);
  for (std::string part; std::getline(stream, part, '/');) {
    if (part.empty()) {
      continue;
    }
    if (!is_identifier(part)) {
      throw RuleError("namespace '" + ns + "' is not a valid ROS namespace");
    }
    out += "/" + part;
  }
  return out;
}

std::string quoted_list(const std::vector<std::string>& items) { return items.empty() ? "none" : join(items, ", "); }

// The variables visible in one launch file.
struct Scope {
  std::string file;
  std::string dir;                            // absolute folder of `file`, for $(dirname)
  std::map<std::string, std::string> values;  // declared arguments
  std::map<std::string, std::string> given;   // command line and include arguments
};

class Loader {
 public:
  explicit Loader(const std::map<std::string, std::string>& overrides) : overrides_(overrides) {}

  LaunchDescription load(const std::string& path) {
    out_.file = path;
    Scope scope;
    scope.given = overrides_;
    load_file(path, scope, 0);
    std::vector<std::string> declared(declared_.begin(), declared_.end());
    for (const auto& [name, value] : overrides_) {
      if (declared_.count(name) == 0) {
        throw LaunchError(path + ": argument '" + name +
                          "' given on the command line is not "
                          "declared by the launch file (declared: " +
                          quoted_list(declared) + ")");
      }
    }
    return out_;
  }

 private:
  void load_file(const std::string& path, Scope scope, int depth) {
    scope.file = path;
    scope.dir = fs::absolute(path).lexically_normal().parent_path().string();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
      throw LaunchError(path + ": launch file not found");
    }
    YAML::Node root;
    try {
      root = YAML::LoadFile(path);
    } catch (const YAML::Exception& e) {
      throw LaunchError(path + ":" + std::to_string(e.mark.line + 1) + ": malformed YAML: " + e.msg);
    }
    if (!root.IsMap()) {
      throw LaunchError(path + ": expected a map with the single key 'launch', got " + type_name(root));
    }
    for (const auto& item : root) {
      if (item.first.as<std::string>() != "launch") {
        throw LaunchError(path + ": unknown top-level key '" + item.first.as<std::string>() + "' (allowed: launch)");
      }
    }
    const YAML::Node entries = static_cast<const YAML::Node&>(root)["launch"];
    if (!entries) {
      throw LaunchError(path + ": missing top-level key 'launch'");
    }
    if (!entries.IsSequence()) {
      throw LaunchError(path + ": 'launch' must be a sequence, got " + type_name(entries));
    }
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const YAML::Node entry = entries[i];
      const int line = entry.Mark().line + 1;
      std::string where = path + ":" + std::to_string(line) + ": launch[" + std::to_string(i) + "]";
      std::string detail;
      try {
        if (!entry.IsMap() || entry.size() != 1) {
          throw RuleError("expected a map with one key (arg, node or include), got " +
                          (entry.IsMap() ? std::to_string(entry.size()) + " keys" : type_name(entry)));
        }
        const std::string kind = entry.begin()->first.as<std::string>();
        const YAML::Node body = entry.begin()->second;
        if (kind != "arg" && kind != "node" && kind != "include") {
          throw RuleError("unknown entry '" + kind + "' (allowed: arg, node, include)");
        }
        where += "." + kind;
        if (!body.IsMap()) {
          throw RuleError("expected a map, got " + type_name(body));
        }
        if (kind == "arg") {
          load_arg(body, scope, detail);
        } else if (kind == "node") {
          load_node(body, scope, detail, path + ":" + std::to_string(line) + " launch[" + std::to_string(i) + "].node");
        } else {
          load_include(body, scope, depth);
        }
      } catch (const RuleError& e) {
        throw LaunchError(where + detail + ": " + e.what());
      }
    }
  }

  // ---- field access -------------------------------------------------------------------

  static void check_keys(const YAML::Node& map, const std::vector<std::string>& allowed, const std::string& field) {
    for (const auto& item : map) {
      const std::string key = item.first.as<std::string>();
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        throw RuleError(field + "unknown key '" + key + "' (allowed: " + join(allowed, ", ") + ")");
      }
    }
  }

  std::optional<std::string> get_string(const YAML::Node& map, const std::string& key, const Scope& scope,
                                        const std::string& field = "") {
    const YAML::Node node = map[key];
    if (!node) {
      return std::nullopt;
    }
    if (!node.IsScalar()) {
      throw RuleError(field + key + " must be a string, got " + type_name(node));
    }
    try {
      return substitute(node.Scalar(), scope);
    } catch (const RuleError& e) {
      throw RuleError(field + key + ": " + e.what());
    }
  }

  std::string require_string(const YAML::Node& map, const std::string& key, const Scope& scope,
                             const std::string& field = "") {
    auto value = get_string(map, key, scope, field);
    if (!value) {
      throw RuleError(field + "missing required key '" + key + "'");
    }
    return *value;
  }

  std::optional<bool> get_bool(const YAML::Node& map, const std::string& key, const Scope& scope) {
    auto text = get_string(map, key, scope);
    if (!text) {
      return std::nullopt;
    }
    std::string lower = *text;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower == "true" || lower == "yes" || lower == "on" || lower == "1") return true;
    if (lower == "false" || lower == "no" || lower == "off" || lower == "0") return false;
    throw RuleError(key + " must be true or false, got '" + *text + "'");
  }

  YAML::Node get_sequence(const YAML::Node& map, const std::string& key) {
    const YAML::Node node = map[key];
    if (node && !node.IsSequence()) {
      throw RuleError(key + " must be a sequence, got " + type_name(node));
    }
    return node;
  }

  // Each element of sequence `key` must be a map with keys among `allowed`.
  YAML::Node get_map_item(const YAML::Node& sequence, std::size_t i, const std::string& key,
                          const std::vector<std::string>& allowed, std::string& field) {
    field = key + "[" + std::to_string(i) + "]: ";
    const YAML::Node item = sequence[i];
    if (!item.IsMap()) {
      throw RuleError(field + "expected a map, got " + type_name(item));
    }
    check_keys(item, allowed, field);
    return item;
  }

  // ---- substitutions ------------------------------------------------------------------

  std::string substitute(const std::string& text, const Scope& scope) {
    std::string out;
    std::size_t i = 0;
    while (i < text.size()) {
      if (text.compare(i, 2, "$(") != 0) {
        out += text[i++];
        continue;
      }
      int depth = 1;
      std::size_t j = i + 2;
      for (; j < text.size() && depth > 0; ++j) {
        if (text.compare(j, 2, "$(") == 0) {
          ++depth;
          ++j;
        } else if (text[j] == ')') {
          --depth;
        }
      }
      if (depth > 0) {
        throw RuleError("unterminated substitution in '" + text + "'");
      }
      out += evaluate(substitute(text.substr(i + 2, j - i - 3), scope), scope);
      i = j;
    }
    return out;
  }

  std::string evaluate(const std::string& expression, const Scope& scope) {
    const std::vector<std::string> words = split_whitespace(expression);
    const std::string what = "$(" + expression + ")";
    const std::string command = words.empty() ? "" : words[0];
    const std::size_t argc = words.size() - (words.empty() ? 0 : 1);
    auto expect = [&](bool ok, const char* usage) {
      if (!ok) throw RuleError(what + ": expected " + usage);
    };
    if (command == "var") {
      expect(argc == 1, "$(var NAME)");
      auto it = scope.values.find(words[1]);
      if (it == scope.values.end()) {
        throw RuleError(what + ": argument '" + words[1] + "' is not declared (add '- arg: {name: " + words[1] +
                        "}' before its use)");
      }
      return it->second;
    }
    if (command == "env") {
      expect(argc >= 1, "$(env VAR) or $(env VAR DEFAULT)");
      if (const char* value = std::getenv(words[1].c_str())) {
        return value;
      }
      if (argc == 1) {
        throw RuleError(what + ": environment variable '" + words[1] + "' is not set");
      }
      return join(std::vector<std::string>(words.begin() + 2, words.end()), " ");
    }
    if (command == "find-pkg-share" || command == "find-pkg-prefix") {
      expect(argc == 1, "one package name");
      auto prefix = find_package_prefix(words[1]);
      if (!prefix) {
        throw RuleError(what + ": " + package_not_found(words[1]));
      }
      return command == "find-pkg-prefix" ? *prefix : *prefix + "/share/" + words[1];
    }
    if (command == "dirname") {
      expect(argc == 0, "no argument");
      return scope.dir;
    }
    throw RuleError("unknown substitution '" + what +
                    "' (supported: var, env, find-pkg-share, find-pkg-prefix, dirname)");
  }

  static std::string package_not_found(const std::string& package) {
    return "package '" + package + "' not found (searched prefixes: " + quoted_list(package_search_prefixes(package)) +
           "; source install/setup.bash or set AMENT_PREFIX_PATH)";
  }

  // ---- entries ------------------------------------------------------------------------

  void load_arg(const YAML::Node& body, Scope& scope, std::string& detail) {
    check_keys(body, {"name", "default", "description"}, "");
    const std::string name = require_string(body, "name", scope);
    detail = " '" + name + "'";
    if (name.empty() || name.find_first_of(" \t$():=") != std::string::npos) {
      throw RuleError("invalid argument name '" + name + "'");
    }
    declared_.insert(name);
    auto given = scope.given.find(name);
    std::string value;
    if (given != scope.given.end()) {
      value = given->second;
    } else if (scope.values.count(name) != 0) {
      value = scope.values[name];
    } else if (auto fallback = get_string(body, "default", scope)) {
      value = *fallback;
    } else {
      throw RuleError("argument '" + name + "' has no default and no value (pass " + name + ":=VALUE)");
    }
    const YAML::Node description = body["description"];
    if (description && !description.IsScalar()) {
      throw RuleError("description must be a string, got " + type_name(description));
    }
    scope.values[name] = value;
    out_.arguments.push_back({name, value, description ? description.Scalar() : "", scope.file});
  }

  void load_node(const YAML::Node& body, const Scope& scope, std::string& detail, const std::string& source) {
    NodeDescription node;
    node.source = source;
    // pkg and exec first, so every later message names the node.
    auto pkg = get_string(body, "pkg", scope);
    auto exec = get_string(body, "exec", scope);
    detail = " (pkg '" + pkg.value_or("?") + "', exec '" + exec.value_or("?") + "')";
    check_keys(body,
               {"pkg", "exec", "name", "namespace", "param", "remap", "args", "ros_args", "env", "respawn",
                "respawn_delay", "required", "on_exit", "output"},
               "");
    if (!pkg) throw RuleError("missing required key 'pkg'");
    if (!exec) throw RuleError("missing required key 'exec'");
    node.package = *pkg;
    node.executable = *exec;
    if (!find_package_prefix(node.package)) {
      throw RuleError(package_not_found(node.package));
    }
    std::vector<std::string> searched;
    auto path = find_executable(node.package, node.executable, &searched);
    if (!path) {
      throw RuleError("executable '" + node.executable + "' not found in package '" + node.package +
                      "' (searched: " + quoted_list(searched) + ")");
    }
    node.executable_path = *path;

    node.name = get_string(body, "name", scope).value_or("");
    if (body["name"] && !is_identifier(node.name)) {
      throw RuleError("name '" + node.name + "' is not a valid ROS node name");
    }
    node.ns = normalize_namespace(get_string(body, "namespace", scope).value_or(""));
    if (!node.name.empty()) {
      const std::string full_name = node.ns + "/" + node.name;
      auto [it, inserted] = node_names_.emplace(full_name, source);
      if (!inserted) {
        throw RuleError("duplicate node name '" + full_name + "' (first declared at " + it->second + ")");
      }
    }

    const YAML::Node params = get_sequence(body, "param");
    for (std::size_t i = 0; params && i < params.size(); ++i) {
      std::string field;
      const YAML::Node item = get_map_item(params, i, "param", {"from", "name", "value"}, field);
      NodeParameter parameter;
      if (item["from"]) {
        if (item["name"] || item["value"]) {
          throw RuleError(field + "use either 'from' or 'name' and 'value', not both");
        }
        parameter.file = require_string(item, "from", scope, field);
        std::error_code ec;
        if (!fs::is_regular_file(parameter.file, ec)) {
          throw RuleError(field + "parameter file '" + parameter.file + "' not found");
        }
      } else {
        parameter.name = require_string(item, "name", scope, field);
        parameter.value = parameter_value(item, scope, field);
        if (parameter.name.empty()) {
          throw RuleError(field + "empty parameter name");
        }
      }
      node.parameters.push_back(parameter);
    }

    const YAML::Node remaps = get_sequence(body, "remap");
    for (std::size_t i = 0; remaps && i < remaps.size(); ++i) {
      std::string field;
      const YAML::Node item = get_map_item(remaps, i, "remap", {"from", "to"}, field);
      const std::string from = require_string(item, "from", scope, field);
      const std::string to = require_string(item, "to", scope, field);
      if (from.empty() || to.empty()) {
        throw RuleError(field + "empty remap '" + from + "' -> '" + to + "'");
      }
      node.remaps.emplace_back(from, to);
    }

    const YAML::Node env = get_sequence(body, "env");
    for (std::size_t i = 0; env && i < env.size(); ++i) {
      std::string field;
      const YAML::Node item = get_map_item(env, i, "env", {"name", "value"}, field);
      const std::string name = require_string(item, "name", scope, field);
      if (name.empty() || name.find('=') != std::string::npos) {
        throw RuleError(field + "invalid environment variable name '" + name + "'");
      }
      node.env.emplace_back(name, require_string(item, "value", scope, field));
    }

    node.args = split_whitespace(get_string(body, "args", scope).value_or(""));
    node.ros_args = split_whitespace(get_string(body, "ros_args", scope).value_or(""));
    node.respawn = get_bool(body, "respawn", scope).value_or(false);
    if (auto delay = get_string(body, "respawn_delay", scope)) {
      char* end = nullptr;
      node.respawn_delay_s = std::strtod(delay->c_str(), &end);
      if (delay->empty() || *end != '\0' || !std::isfinite(node.respawn_delay_s) || node.respawn_delay_s < 0.0) {
        throw RuleError("respawn_delay must be a number of seconds >= 0, got '" + *delay + "'");
      }
    }
    node.required = get_bool(body, "required", scope).value_or(false);
    if (auto on_exit = get_string(body, "on_exit", scope)) {
      if (*on_exit != "shutdown") {
        throw RuleError("on_exit must be 'shutdown', got '" + *on_exit + "'");
      }
      node.required = true;
    }
    node.output = get_string(body, "output", scope).value_or("screen");
    if (node.output != "screen" && node.output != "log" && node.output != "both") {
      throw RuleError("output must be screen, log or both, got '" + node.output + "'");
    }
    out_.nodes.push_back(std::move(node));
  }

  // A scalar, or a sequence of scalars written as a YAML flow list "[a, b]".
  std::string parameter_value(const YAML::Node& item, const Scope& scope, const std::string& field) {
    const YAML::Node value = item["value"];
    if (value && value.IsSequence()) {
      std::vector<std::string> elements;
      for (const auto& element : value) {
        if (!element.IsScalar()) {
          throw RuleError(field + "value must be a scalar or a list of scalars");
        }
        elements.push_back(substitute(element.Scalar(), scope));
      }
      return "[" + join(elements, ", ") + "]";
    }
    return require_string(item, "value", scope, field);
  }

  void load_include(const YAML::Node& body, const Scope& scope, int depth) {
    check_keys(body, {"file", "arg"}, "");
    std::string file = require_string(body, "file", scope);
    if (fs::path(file).is_relative()) {
      file = (fs::path(scope.dir) / file).lexically_normal().string();
    }
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) {
      throw RuleError("included file '" + file + "' not found");
    }
    if (depth + 1 > kMaxIncludeDepth) {
      throw RuleError("includes nested deeper than " + std::to_string(kMaxIncludeDepth) + " (recursive include of '" +
                      file + "'?)");
    }
    Scope child;
    child.values = scope.values;
    child.given = scope.given;
    const YAML::Node args = get_sequence(body, "arg");
    for (std::size_t i = 0; args && i < args.size(); ++i) {
      std::string field;
      const YAML::Node item = get_map_item(args, i, "arg", {"name", "value"}, field);
      child.given[require_string(item, "name", scope, field)] = require_string(item, "value", scope, field);
    }
    load_file(file, child, depth + 1);
  }

  const std::map<std::string, std::string>& overrides_;
  std::set<std::string> declared_;
  std::map<std::string, std::string> node_names_;  // full name -> source
  LaunchDescription out_;
};

}  // namespace

LaunchDescription load_launch_file(const std::string& path, const std::map<std::string, std::string>& arg_overrides) {
  return Loader(arg_overrides).load(path);
}

std::map<std::string, std::string> parse_launch_arguments(const std::vector<std::string>& items) {
  std::map<std::string, std::string> out;
  for (const auto& item : items) {
    const std::size_t pos = item.find(":=");
    if (pos == std::string::npos || pos == 0) {
      throw LaunchError("launch argument '" + item + "' is not of the form NAME:=VALUE");
    }
    out[item.substr(0, pos)] = item.substr(pos + 2);
  }
  return out;
}

std::vector<std::string> node_argv(const NodeDescription& node) {
  std::vector<std::string> argv{node.executable_path};
  argv.insert(argv.end(), node.args.begin(), node.args.end());
  std::vector<std::string> ros;
  if (!node.name.empty()) {
    ros.insert(ros.end(), {"-r", "__node:=" + node.name});
  }
  if (!node.ns.empty()) {
    ros.insert(ros.end(), {"-r", "__ns:=" + node.ns});
  }
  for (const auto& parameter : node.parameters) {
    if (!parameter.file.empty()) {
      ros.insert(ros.end(), {"--params-file", parameter.file});
    } else {
      ros.insert(ros.end(), {"-p", parameter.name + ":=" + parameter.value});
    }
  }
  for (const auto& [from, to] : node.remaps) {
    ros.insert(ros.end(), {"-r", from + ":=" + to});
  }
  ros.insert(ros.end(), node.ros_args.begin(), node.ros_args.end());
  if (!ros.empty()) {
    argv.push_back("--ros-args");
    argv.insert(argv.end(), ros.begin(), ros.end());
  }
  return argv;
}

}  // namespace unav::launch
