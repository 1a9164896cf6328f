// `unav security create_keystore | create_enclave | create_permission | list_enclaves |
// generate_artifacts`, like `ros2 security` (SROS2): keystores the ROS_SECURITY_* switches use.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace unav::cli {

/// Adds the `security` subcommand to `app`; returns the function that runs whichever verb was
/// parsed (call it after parsing when the `security` subcommand was given).
std::function<int()> add_security_command(CLI::App& app);

}  // namespace unav::cli
