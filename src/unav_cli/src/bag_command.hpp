// `unav bag record | play | info`, like `ros2 bag`: the DDS side of unav_bag.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace unav::cli {

/// Adds the `bag` subcommand to `app`; returns the function that runs whichever verb was parsed
/// (call it after parsing when the `bag` subcommand was given).
std::function<int()> add_bag_command(CLI::App& app);

}  // namespace unav::cli
