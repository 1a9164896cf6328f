// Typed configuration errors. They are thrown at configure time (node construction, argument
// parsing) with a message naming the file, key, value and rule; run_node() turns them into a
// one-line error and exit code 2.
#pragma once

#include <stdexcept>
#include <string>

#include "unav_common/errors.hpp"  // unav::ConfigError (file, key, value, rule)

namespace unav {

struct NameError : ConfigError {
  using ConfigError::ConfigError;
};
struct ParameterError : ConfigError {
  using ConfigError::ConfigError;
};
struct ArgumentError : ConfigError {
  using ConfigError::ConfigError;
};
/// The middleware refused something (no participant, type clash...): not the user's config.
struct MiddlewareError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace unav
