// Logging with the node name, ROS 2 console format: "[INFO] [1700000000.123456789] [talker]: text".
#pragma once

#include <memory>
#include <string>

#include <spdlog/spdlog.h>

namespace unav {

using Logger = std::shared_ptr<spdlog::logger>;

/// A logger named after the node (fully qualified name without the leading '/', dots for
/// slashes, as ROS 2 names loggers). Writes to stderr, flushed at every warning and above.
Logger make_logger(const std::string& name);
/// Sets the level of every logger made from now on and of those made before: debug..fatal.
void set_log_level(const std::string& level);

}  // namespace unav
