// Validating YAML access: every error names the file and the key path (STYLE.md rule 6).
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <initializer_list>
#include <string>

#include "unav_scene/errors.hpp"

namespace unav::scene::detail {

struct YamlCtx {
  std::string file;
  [[noreturn]] void fail(const std::string& key, const std::string& why) const {
    throw ConfigError(file + ": " + (key.empty() ? std::string("<root>") : key) + ": " + why);
  }
};

inline std::string join_key(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

inline void check_keys(const YamlCtx& c, const YAML::Node& n, const std::string& path,
                       std::initializer_list<const char*> allowed) {
  if (!n) return;
  if (!n.IsMap()) c.fail(path, "expected a mapping");
  for (const auto& kv : n) {
    const auto k = kv.first.as<std::string>();
    bool ok = false;
    for (const char* a : allowed) ok = ok || k == a;
    if (!ok) {
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
      c.fail(join_key(path, k), "unknown key (allowed: " + list + ")");
    }
  }
}

inline double get_double(const YamlCtx& c, const YAML::Node& n, const std::string& path,
                         const char* key, double def) {
  const auto v = n[key];
  if (!v) return def;
  try {
    return v.as<double>();
  } catch (const YAML::Exception&) {
    c.fail(join_key(path, key), "expected a number");
  }
}

inline std::string get_string(const YamlCtx& c, const YAML::Node& n, const std::string& path,
                              const char* key, const std::string& def) {
  const auto v = n[key];
  if (!v) return def;
  if (!v.IsScalar()) c.fail(join_key(path, key), "expected a string");
  return v.as<std::string>();
}

inline bool get_bool(const YamlCtx& c, const YAML::Node& n, const std::string& path,
                     const char* key, bool def) {
  const auto v = n[key];
  if (!v) return def;
  try {
    return v.as<bool>();
  } catch (const YAML::Exception&) {
    c.fail(join_key(path, key), "expected true/false");
  }
}

/// A list of N numbers (N = 2 or 3); a scalar x is accepted as (x, x, x) when allow_scalar.
template <int N>
inline Eigen::Matrix<double, N, 1> get_vec(const YamlCtx& c, const YAML::Node& n,
                                           const std::string& path, const char* key,
                                           const Eigen::Matrix<double, N, 1>& def,
                                           bool allow_scalar = false) {
  const auto v = n[key];
  if (!v) return def;
  Eigen::Matrix<double, N, 1> out;
  try {
    if (v.IsScalar() && allow_scalar) {
      out.setConstant(v.as<double>());
      return out;
    }
    if (!v.IsSequence() || static_cast<int>(v.size()) != N)
      c.fail(join_key(path, key), "expected a list of " + std::to_string(N) + " numbers");
    for (int i = 0; i < N; ++i) out[i] = v[i].as<double>();
  } catch (const YAML::Exception&) {
    c.fail(join_key(path, key), "expected a list of " + std::to_string(N) + " numbers");
  }
  return out;
}

inline YAML::Node load_yaml_file(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open file");
  } catch (const YAML::ParserException& e) {
    throw ConfigError(path + ": YAML syntax error: " + e.what());
  }
}

}  // namespace unav::scene::detail
