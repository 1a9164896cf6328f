// What the `unav` verbs share: the user-facing error, the IDL registry, topic name resolution.
#pragma once

#include <chrono>
#include <cstdint>
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

/// Wall-clock time (system clock) in nanoseconds since the epoch: the receive stamp of recorded
/// and forwarded samples.
inline int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// "imu" -> "/imu", as ros2 resolves a topic given on the command line.
std::string normalize_topic(const std::string& topic);

}  // namespace unav::cli
