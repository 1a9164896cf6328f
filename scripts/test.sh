#!/usr/bin/env bash
# README command 2: install what is missing, build, run every test; non-zero exit on any failure.
set -eo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
# Tests and benchmarks on, also in a tree that README command 1 configured without them.
bash scripts/build.sh -DBUILD_TESTING=ON
colcon test --executor sequential --event-handlers console_cohesion- status- --return-code-on-test-failure "$@" || rc=$?
colcon test-result --verbose | tee log/test_result.txt
# One plain closing line for CI: "N passed, N failed".
read -r total errors failures skipped < <(sed -n 's/^Summary: \([0-9]*\) tests, \([0-9]*\) errors, \([0-9]*\) failures, \([0-9]*\) skipped$/\1 \2 \3 \4/p' log/test_result.txt | tail -1)
if [ -n "${total:-}" ]; then
  echo "$((total - errors - failures - skipped)) passed, $((errors + failures)) failed, $skipped skipped"
  [ "$total" -gt 0 ] || { echo "no test ran"; exit 1; }
fi
exit "${rc:-0}"
