// The one configuration error of the workspace (STYLE.md item 7, tier 2): thrown at configure
// time (loading a config, parsing arguments, building a node) with the offending file, key,
// value and rule, e.g. "config/controllers/mpc.yaml: horizon_steps = -3: must be >= 1".
// Nodes catch it at their boundary (run_node) and turn it into one line and exit code 2.
#pragma once

#include <stdexcept>
#include <string>

namespace unav {

class ConfigError : public std::runtime_error {
 public:
  /// A ready-made message (file, key and value already in it).
  explicit ConfigError(const std::string& message);
  /// Message "FILE: KEY = VALUE: RULE"; empty parts are left out ("FILE: KEY: RULE" without a
  /// value, "FILE: RULE" without key and value, "KEY = VALUE: RULE" without a file).
  ConfigError(std::string file, std::string key, std::string value, std::string rule);
  ~ConfigError() override;
  ConfigError(const ConfigError&) = default;
  ConfigError& operator=(const ConfigError&) = default;

  /// The parts given to the four-part constructor; empty for the one-message form.
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }
  const std::string& value() const { return value_; }
  const std::string& rule() const { return rule_; }

  /// The message the four-part constructor builds (exposed for callers formatting alike).
  static std::string Format(const std::string& file, const std::string& key, const std::string& value,
                            const std::string& rule);

 private:
  std::string file_, key_, value_, rule_;
};

}  // namespace unav
