// Internal to unav_common (config.cpp): the leaf values of the config schema, one switch over
// ValueType each (config_values.cpp), for the archives of config.cpp.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_common/config.hpp"

namespace unav::common::config_values {

/// Where errors go: ConfigError(file, key path, value text, rule).
struct Reporter {
  std::string file;
  [[noreturn]] void Fail(const std::string& path, const std::string& value, const std::string& rule) const {
    throw ConfigError(file, path, value, rule);
  }
};

/// A string as a double-quoted YAML scalar.
std::string StringText(const std::string& s);
std::string JoinTexts(const std::vector<std::string>& items);
/// The current value as flow YAML text.
std::string ValueText(ValueRef v);
const char* TypeName(ValueType t);
/// The value of a YAML node as it was written (scalars as text, collections in flow style).
std::string Written(const YAML::Node& n);
std::string ChildPath(const std::string& parent, const std::string& name);
std::string IndexPath(const std::string& parent, std::size_t i);
/// A field's numeric rule as text ("in [1, 500]", "> 0", ...).
std::string NumberRule(const FieldSpec& s);

/// Tag of the maps ApplyOverride builds for "name[i]" (index -> value); never read from files.
extern const char* kIndexTag;
bool ParseIndex(const std::string& text, std::size_t* out);

/// Reads a leaf value from `n` into `v`, checking type and rule (unchanged on error).
void ReadValue(const Reporter& r, const FieldSpec& s, const YAML::Node& n, ValueRef v, const std::string& path,
               bool allow_index_map);
/// Checks a leaf's current value against its rule (Validate).
void CheckValue(const Reporter& r, const FieldSpec& s, ValueRef v, const std::string& path);
/// A leaf as a YAML node (numbers and strings as plain scalars, lists in flow style).
YAML::Node ValueNode(ValueRef v);

}  // namespace unav::common::config_values
