#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the pipe-inspection demo headless on
# defaults: physics (1 kHz, lockstep) + underwater renderer (front and down cameras) + dataset
# recorder, as separate processes over DDS. Stops after DEMO_SIM_SECONDS of simulated time.
set -eo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
source install/setup.bash
set -u
OUT="${UNAV_OUT:-$PWD/out/demo}"
SIM_SECONDS="${DEMO_SIM_SECONDS:-20}"
rm -rf "$OUT" && mkdir -p "$OUT"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-42}"
echo "demo: pipe inspection, ${SIM_SECONDS} s of simulated time, DDS domain $ROS_DOMAIN_ID"
unav launch launch_scripts/pipe_inspection.launch.yaml output_dir:="$OUT/dataset" > "$OUT/launch.log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true' EXIT
frames_wanted=$(awk -v s="$SIM_SECONDS" 'BEGIN{print int(s * 10) + 1}')
for _ in $(seq 1 600); do
  n=$(grep -vc '^#' "$OUT/dataset/rgb.txt" 2>/dev/null || true)
  [ "${n:-0}" -ge "$frames_wanted" ] && break
  kill -0 "$launch_pid" 2>/dev/null || { echo "demo: launch ended early; see $OUT/launch.log"; exit 1; }
  sleep 1
done
unav topic list -t > "$OUT/topics.txt"
kill -INT "$launch_pid"
wait "$launch_pid" || true
trap - EXIT
frames=$(grep -vc '^#' "$OUT/dataset/rgb.txt")
echo "demo: finished: $frames frames with depth, segmentation, ground truth and IMU"
echo "demo: outputs in $OUT:"
echo "  dataset/ (TUM RGB-D layout: rgb/ depth/ segmentation/ rgb.txt depth.txt groundtruth.txt imu.txt camera.yaml)"
echo "  launch.log (all node output), topics.txt (the ROS 2 topics that were live)"
