#!/usr/bin/env bash
# Builds the workspace with colcon (Release with debug info), two jobs at most by default.
set -euo pipefail
cd "$(dirname "$0")/.."
export MAKEFLAGS="${MAKEFLAGS:--j$(nproc)}"
colcon build --event-handlers console_cohesion- status- --cmake-args -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@"
