// `unav foxglove`: a live view of the running system in Foxglove (or Lichtblick), as
// foxglove_bridge gives ROS 2: a Foxglove WebSocket server (foxglove_server.hpp) that advertises
// every topic with a publisher (or the topics named) with its ros2msg schema and forwards the CDR
// samples of the topics a client subscribes to. DDS subscriptions exist only while a client wants
// the topic.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace unav::cli {

/// Adds the `foxglove` subcommand to `app`; returns the function that runs it after parsing.
std::function<int()> add_foxglove_command(CLI::App& app);

}  // namespace unav::cli
