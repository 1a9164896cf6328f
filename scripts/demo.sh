#!/usr/bin/env bash
# README command 1: install what is missing, build, run the main job headless on defaults.
# Until the pipe-inspection demo lands, the main job is the smallest real multi-process system:
# a talker and a listener started by `unav launch`, watched by `unav topic echo` and `node list`.
set -eo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
source install/setup.bash
set -u
OUT="${UNAV_OUT:-$PWD/out/demo}"
mkdir -p "$OUT"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-42}"
echo "demo: launching talker + listener (two processes) on DDS domain $ROS_DOMAIN_ID"
unav launch launch_scripts/talker_listener.launch.yaml rate:=10.0 count:=100 > "$OUT/launch.log" 2>&1 &
launch_pid=$!
timeout -s INT 20 unav topic echo /demo/chatter --once | tee "$OUT/echo.txt"
unav node list | tee "$OUT/nodes.txt"
unav topic list -t | tee "$OUT/topics.txt"
timeout -s INT 3 unav topic hz /demo/chatter | tee "$OUT/hz.txt" || true   # hz runs until stopped
wait "$launch_pid"
echo "demo: finished; outputs in $OUT (launch.log, echo.txt, nodes.txt, topics.txt, hz.txt)"
