#!/usr/bin/env bash
# README command 2: install what is missing, build, run every test; non-zero exit on any failure.
set -eo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
colcon test --executor sequential --event-handlers console_cohesion- status- --return-code-on-test-failure "$@" || rc=$?
colcon test-result --verbose
exit "${rc:-0}"
