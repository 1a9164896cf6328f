#!/usr/bin/env bash
# Frames/s, bandwidth and latency through `unav foxglove` for the 640x480 front camera, raw and
# compressed, with the bridge's CPU: teleop.launch.yaml in real time, the bridge, and Foxglove's
# own client (src/unav_bag/test/foxglove/foxglove_client.mjs measure). Latency is from the
# bridge taking the sample off DDS (before compressing it) to the client having decoded it.
#   bash scripts/bench_foxglove.sh [SECONDS_PER_CASE]      (after scripts/build.sh)
set -euo pipefail
ws="$(cd "$(dirname "$0")/.." && pwd)"
secs="${1:-15}"
set +u; source "$ws/install/setup.bash"; set -u
client="$ws/src/unav_bag/test/foxglove/foxglove_client.mjs"
log=$(mktemp); blog=$(mktemp)
port=$((20000 + RANDOM % 20000))
unav launch "$ws/launch_scripts/teleop.launch.yaml" >"$log" 2>&1 &
launch_pid=$!
unav foxglove --port "$port" >"$blog" 2>&1 &
bridge_pid=$!
trap 'kill -INT $launch_pid $bridge_pid 2>/dev/null || true; wait $launch_pid $bridge_pid 2>/dev/null || true; rm -f "$log" "$blog"' EXIT
cpu_s() { awk '{print ($14 + $15) / 100}' "/proc/$bridge_pid/stat"; }  # utime + stime, 100 ticks/s
sleep 5
echo "# $(uname -n), $(nproc) cores, $(date -u +%FT%TZ), $(git -C "$ws" rev-parse --short HEAD)"
for topic in /rov/camera/front/image_raw /rov/camera/front/image_raw/compressed; do
  c0=$(cpu_s)
  r=$(node "$client" "ws://127.0.0.1:$port" measure "$topic" "$secs")
  c1=$(cpu_s)
  echo "$r" | sed "s/}\$/,\"bridge_cpu_percent\":$(awk -v a="$c0" -v b="$c1" -v s="$secs" 'BEGIN{printf "%.1f", 100*(b-a)/s}')}/"
done
