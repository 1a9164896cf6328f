#include "unav_common/errors.hpp"

#include <utility>

namespace unav {

ConfigError::ConfigError(const std::string& message) : std::runtime_error(message) {}

ConfigError::ConfigError(std::string file, std::string key, std::string value, std::string rule)
    : std::runtime_error(Format(file, key, value, rule)),
      file_(std::move(file)),
      key_(std::move(key)),
      value_(std::move(value)),
      rule_(std::move(rule)) {}

ConfigError::~ConfigError() = default;

std::string ConfigError::Format(const std::string& file, const std::string& key, const std::string& value,
                                const std::string& rule) {
  const std::string subject = key.empty() ? value : value.empty() ? key : key + " = " + value;
  std::string out;
  for (const std::string* part : {&file, &subject, &rule}) {
    if (part->empty()) continue;
    if (!out.empty()) out += ": ";
    out += *part;
  }
  return out;
}

}  // namespace unav
