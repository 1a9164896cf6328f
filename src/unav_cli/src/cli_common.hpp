// What the `unav` verbs share: the user-facing error, the IDL registry, topic name resolution.
#pragma once

#include <stdexcept>
#include <string>

#include "unav_introspection/type_registry.hpp"

namespace unav::cli {

/// A user-facing error: printed as one line, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// IDL types of every installed interface package (environment and this executable's prefix).
unav::introspection::TypeRegistry make_registry();

/// "imu" -> "/imu", as ros2 resolves a topic given on the command line.
std::string normalize_topic(const std::string& topic);

}  // namespace unav::cli
