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

void flatten(const YAML::Node& node, const std::string& prefix, const std::string& source,
             std::map<std::string, ParameterOverride>& out) {
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    const std::string name = prefix.empty() ? key : prefix + "." + key;
    if (kv.second.IsMap())
      flatten(kv.second, name, source, out);
    else
      out[name] = ParameterOverride{kv.second, source};
  }
}

std::string show(const YAML::Node& v) {
  YAML::Emitter e;
  e << YAML::Flow << v;
  return e.c_str();
}

[[noreturn]] void type_error(const std::string& context, const char* type, const YAML::Node& v) {
  throw ParameterError(context + ": expected " + type + ", got '" + show(v) + "'");
}

bool parse_bool(const YAML::Node& v, const std::string& ctx) {
  if (!v.IsScalar()) type_error(ctx, "bool", v);
  const std::string s = v.Scalar();
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  type_error(ctx, "bool (true or false)", v);
}

int64_t parse_int(const YAML::Node& v, const std::string& ctx) {
  if (!v.IsScalar() || v.Tag() == "!") type_error(ctx, "integer", v);
  const std::string s = v.Scalar();
  errno = 0;
  char* end = nullptr;
  const long long x = std::strtoll(s.c_str(), &end, 0);
  if (s.empty() || *end != '\0') type_error(ctx, "integer", v);
  if (errno == ERANGE) throw ParameterError(ctx + ": value '" + s + "' does not fit in a 64-bit integer");
  return x;
}

double parse_double(const YAML::Node& v, const std::string& ctx) {
  if (!v.IsScalar() || v.Tag() == "!") type_error(ctx, "double", v);
  std::string s = v.Scalar();
  if (s == ".nan" || s == ".NaN" || s == ".NAN") return std::numeric_limits<double>::quiet_NaN();
  if (s == ".inf" || s == ".Inf" || s == "+.inf") return std::numeric_limits<double>::infinity();
  if (s == "-.inf" || s == "-.Inf") return -std::numeric_limits<double>::infinity();
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0') type_error(ctx, "double", v);
  return x;
}

void check_number(double x, const ParameterDescriptor& d, const std::string& ctx) {
  if (!std::isfinite(x) && !d.allow_non_finite)
    throw ParameterError(ctx + ": value " + std::to_string(x) + " must be finite (NaN/Inf rejected)");
  if ((d.min && x < *d.min) || (d.max && x > *d.max)) {
    std::ostringstream os;
    os << ctx << ": value " << x << " is out of range [" << (d.min ? std::to_string(*d.min) : "-inf") << ", "
       << (d.max ? std::to_string(*d.max) : "inf") << "]";
    throw ParameterError(os.str());
  }
}

template <typename E>
std::vector<E> parse_array(const YAML::Node& v, const ParameterDescriptor& d, const std::string& ctx) {
  if (!v.IsSequence()) type_error(ctx, parameter_type_name<std::vector<E>>(), v);
  std::vector<E> out;
  for (size_t i = 0; i < v.size(); ++i)
    out.push_back(parameter_as<E>(v[i], d, ctx + "[" + std::to_string(i) + "]"));
  return out;
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
    if (!root.IsMap())
      throw ParameterError("params file '" + file + "': top level must be a map of node names");
    for (const auto& entry : root) {
      const std::string key = entry.first.as<std::string>();
      const YAML::Node body = entry.second;
      if (!body.IsMap() || !body["ros__parameters"])
        throw ParameterError("params file '" + file + "': key '" + key +
                             "' must contain 'ros__parameters' (layout: node_name: {ros__parameters: {...}})");
      for (const auto& k : body)
        if (k.first.as<std::string>() != "ros__parameters")
          throw ParameterError("params file '" + file + "': key '" + key + "." + k.first.as<std::string>() +
                               "' is unknown (only 'ros__parameters' is allowed there)");
      if (!key_matches_node(key, node_namespace, node_name)) continue;
      const YAML::Node params = body["ros__parameters"];
      if (!params.IsMap() && !params.IsNull())
        throw ParameterError("params file '" + file + "': '" + key + ".ros__parameters' must be a map");
      if (params.IsMap()) flatten(params, "", "params file '" + file + "'", values_);
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

template <> const char* parameter_type_name<bool>() { return "bool"; }
template <> const char* parameter_type_name<int>() { return "integer"; }
template <> const char* parameter_type_name<int64_t>() { return "integer"; }
template <> const char* parameter_type_name<double>() { return "double"; }
template <> const char* parameter_type_name<std::string>() { return "string"; }
template <> const char* parameter_type_name<std::vector<bool>>() { return "bool array"; }
template <> const char* parameter_type_name<std::vector<int64_t>>() { return "integer array"; }
template <> const char* parameter_type_name<std::vector<double>>() { return "double array"; }
template <> const char* parameter_type_name<std::vector<std::string>>() { return "string array"; }

template <> bool parameter_as<bool>(const YAML::Node& v, const ParameterDescriptor&, const std::string& ctx) {
  return parse_bool(v, ctx);
}
template <> int64_t parameter_as<int64_t>(const YAML::Node& v, const ParameterDescriptor& d, const std::string& ctx) {
  const int64_t x = parse_int(v, ctx);
  check_number(static_cast<double>(x), d, ctx);
  return x;
}
template <> int parameter_as<int>(const YAML::Node& v, const ParameterDescriptor& d, const std::string& ctx) {
  const int64_t x = parameter_as<int64_t>(v, d, ctx);
  if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max())
    throw ParameterError(ctx + ": value " + std::to_string(x) + " does not fit in a 32-bit integer");
  return static_cast<int>(x);
}
template <> double parameter_as<double>(const YAML::Node& v, const ParameterDescriptor& d, const std::string& ctx) {
  const double x = parse_double(v, ctx);
  check_number(x, d, ctx);
  return x;
}
template <>
std::string parameter_as<std::string>(const YAML::Node& v, const ParameterDescriptor&, const std::string& ctx) {
  if (v.IsNull()) return "";  // `-p name:=` (empty) is the empty string, as in ROS 2
  if (!v.IsScalar()) type_error(ctx, "string", v);
  return v.Scalar();
}
template <>
std::vector<bool> parameter_as<std::vector<bool>>(const YAML::Node& v, const ParameterDescriptor& d,
                                                  const std::string& ctx) {
  return parse_array<bool>(v, d, ctx);
}
template <>
std::vector<int64_t> parameter_as<std::vector<int64_t>>(const YAML::Node& v, const ParameterDescriptor& d,
                                                        const std::string& ctx) {
  return parse_array<int64_t>(v, d, ctx);
}
template <>
std::vector<double> parameter_as<std::vector<double>>(const YAML::Node& v, const ParameterDescriptor& d,
                                                      const std::string& ctx) {
  return parse_array<double>(v, d, ctx);
}
template <>
std::vector<std::string> parameter_as<std::vector<std::string>>(const YAML::Node& v, const ParameterDescriptor& d,
                                                                const std::string& ctx) {
  return parse_array<std::string>(v, d, ctx);
}

}  // namespace unav
