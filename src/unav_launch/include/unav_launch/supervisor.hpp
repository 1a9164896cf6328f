// Runs the nodes of a LaunchDescription as child processes, like `ros2 launch`.
//
// Each node runs in its own process group and gets PR_SET_PDEATHSIG(SIGTERM), so nothing
// outlives a killed launcher. Its stdout and stderr go through one pipe and are printed whole
// lines at a time as "[<exec>-<n>] line" (n = 1-based position in the description).
//
// Shutdown (SIGINT/SIGTERM to the launcher, or a required node exiting): SIGINT to every
// node's process group, SIGTERM after `sigint_grace_s`, SIGKILL after `sigterm_grace_s` more;
// further SIGINT/SIGTERM are logged and ignored. When a node's main process exits, what is
// left of its process group is SIGKILLed. run() returns only after every child is reaped.
#pragma once

#include <iostream>
#include <ostream>

#include "unav_launch/launch_description.hpp"

namespace unav::launch {

/// How run() shuts down and where it writes.
struct SupervisorOptions {
  double sigint_grace_s = 5.0;   ///< Wait after SIGINT before SIGTERM [s].
  double sigterm_grace_s = 5.0;  ///< Wait after SIGTERM before SIGKILL [s].
  std::ostream* out = &std::cout;  ///< Prefixed node output and "[INFO] [launch]: ..." lines.
};

/// Starts every node in order and supervises them until all have exited; single-threaded,
/// blocking. Installs handlers for SIGINT, SIGTERM, SIGCHLD (and ignores SIGPIPE) for its
/// duration and restores the previous ones; at most one run() per process at a time, called
/// from the thread that should count as the nodes' parent (PR_SET_PDEATHSIG).
/// Returns:
///  - 0 when every node exited on its own with code 0 (also for an empty description);
///  - 1 when every node exited on its own and one of them failed;
///  - the exit code of a required node that exited (0 when it finished cleanly), or 1 if a signal
///    killed it;
///  - 128 + signal number when SIGINT/SIGTERM stopped the launch.
/// Exits during shutdown do not count. Respawning nodes restart after respawn_delay_s
/// unless a shutdown is under way.
int run(const LaunchDescription& description, const SupervisorOptions& options = {});

}  // namespace unav::launch
