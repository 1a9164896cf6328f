#include "unav_runtime/parameters.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

#include "unav_runtime/errors.hpp"

namespace unav {
namespace {

// "/**" matches any number of segments, "*" exactly one; keys without a leading '/' are
// relative to the root.
bool glob_match(const std::vector<std::string>& pat, size_t pi, const std::vector<std::string>& name, size_t ni) {
  if (pi == pat.size()) return ni == name.size();
  if (pat[pi] == "**") {
    for (size_t k = ni; k <= name.size(); ++k)
      if (glob_match(pat, pi + 1, name, k)) return true;
    return false;
  }
  if (ni == name.size()) return false;
  return (pat[pi] == "*" || pat[pi] == name[ni]) && glob_match(pat, pi + 1, name, ni + 1);
}

std::vector<std::string> split_path(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, '/'))
    if (!tok.empty()) out.push_back(tok);
  return out;
}

bool key_matches_node(const std::string& key, const std::string& ns, const std::string& node) {
  std::vector<std::string> fqn = split_path(ns);
  fqn.push_back(node);
  const std::vector<std::string> pat = split_path(key);
  // A bare node name ("talker:") matches that node in any namespace, as ROS 2 does.
  if (key.find('/') == std::string::npos) return key == node || key == "*" || key == "**";
  return glob_match(pat, 0, fqn, 0);
}

// A map key as text; a key that is itself a list or a map (YAML `? [a, b]: v`) names nothing.
std::string key_text(const YAML::Node& key, const std::string& file, const std::string& where) {
  if (!key.IsScalar())
    throw ParameterError("params file '" + file + "': a key " + where + " at line " +
                         std::to_string(key.Mark().line + 1) + " is a " +
                         (key.IsSequence() ? "list"
                          : key.IsMap()    ? "map"
                                           : "null") +
                         ": keys must be node or parameter names");
  return key.Scalar();
}

void flatten(const YAML::Node& node, const std::string& prefix, const std::string& file,
             std::map<std::string, ParameterOverride>& out) {
  for (const auto& kv : node) {
    const std::string key = key_text(kv.first, file, prefix.empty() ? "in ros__parameters" : "under '" + prefix + "'");
    const std::string name = prefix.empty() ? key : prefix + "." + key;
    if (kv.second.IsMap())
      flatten(kv.second, name, file, out);
    else
      out[name] = ParameterOverride{kv.second, "params file '" + file + "'"};
  }
}

}  // namespace

ParameterOverrides::ParameterOverrides(const RosArgs& args, const std::string& node_namespace,
                                       const std::string& node_name) {
  for (const auto& file : args.params_files) {
    std::ifstream in(file);
    if (!in) throw ParameterError("params file '" + file + "': cannot be opened (missing or unreadable)");
    YAML::Node root;
    try {
      root = YAML::LoadFile(file);
    } catch (const YAML::Exception& e) {
      throw ParameterError("params file '" + file + "': malformed YAML at line " + std::to_string(e.mark.line + 1) +
                           ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
    }
    if (root.IsNull()) continue;
    if (!root.IsMap()) throw ParameterError("params file '" + file + "': top level must be a map of node names");
    for (const auto& entry : root) {
      const std::string key = key_text(entry.first, file, "at the top level");
      const YAML::Node body = entry.second;
      if (!body.IsMap() || !body["ros__parameters"])
        throw ParameterError("params file '" + file + "': key '" + key +
                             "' must contain 'ros__parameters' (layout: node_name: {ros__parameters: {...}})");
      for (const auto& k : body) {
        const std::string sub = key_text(k.first, file, "under '" + key + "'");
        if (sub != "ros__parameters")
          throw ParameterError("params file '" + file + "': key '" + key + "." + sub +
                               "' is unknown (only 'ros__parameters' is allowed there)");
      }
      if (!key_matches_node(key, node_namespace, node_name)) continue;
      const YAML::Node params = body["ros__parameters"];
      if (!params.IsMap() && !params.IsNull())
        throw ParameterError("params file '" + file + "': '" + key + ".ros__parameters' must be a map");
      if (params.IsMap()) flatten(params, "", file, values_);
    }
  }
  for (const auto& p : args.params) {
    if (!p.node.empty() && p.node != node_name) continue;
    YAML::Node v;
    try {
      v = YAML::Load(p.value);
    } catch (const YAML::Exception& e) {
      throw ParameterError("command line '-p " + p.name + ":=" + p.value + "': malformed YAML value: " + e.msg);
    }
    values_[p.name] = ParameterOverride{v, "command line '-p " + p.name + ":=" + p.value + "'"};
  }
}

const ParameterOverride* ParameterOverrides::find(const std::string& name) const {
  const auto it = values_.find(name);
  return it == values_.end() ? nullptr : &it->second;
}

std::vector<std::string> ParameterOverrides::unused() const {
  std::vector<std::string> out;
  for (const auto& kv : values_)
    if (std::find(used_.begin(), used_.end(), kv.first) == used_.end()) out.push_back(kv.first);
  return out;
}

}  // namespace unav
