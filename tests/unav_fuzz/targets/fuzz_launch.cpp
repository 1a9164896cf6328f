// The launch-file loader (`unav launch`) on arbitrary YAML: must give LaunchError (or a clear
// config error) and start nothing.
#include <stdexcept>

#include "fuzz_common.hpp"
#include "unav_launch/launch_description.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = unav::fuzz::write_input(data, size, ".launch.yaml");
  try {
    const auto d = unav::launch::load_launch_file(path, {});
    for (const auto& n : d.nodes) (void)unav::launch::node_argv(n);
  } catch (const std::runtime_error&) {  // LaunchError, ConfigError
  }
  return 0;
}
