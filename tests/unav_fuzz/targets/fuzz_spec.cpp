// The domain-randomization spec of `unav datagen` on arbitrary YAML: must give ConfigError (or a
// YAML parse error) before any work; a spec that parses must sample.
#include <yaml-cpp/yaml.h>

#include <string>

#include "unav_common/errors.hpp"
#include "unav_datagen/randomization.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const YAML::Exception&) {
    return 0;
  }
  try {
    const auto spec = unav::datagen::RandomizationSpec::parse(root, UNAV_WS "/config/datagen/fuzz.yaml");
    (void)spec.sample(0);
    (void)spec.sample(1);
  } catch (const unav::ConfigError&) {
  }
  return 0;
}
