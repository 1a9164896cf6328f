#!/usr/bin/env bash
# Re-trains config/vocabulary/orb_vocabulary.bin, the bag-of-words vocabulary of the ORB SLAM's
# loop detection and relocalisation, on rendered images that are NOT the benchmark's: the down
# camera (640 x 480) flown 2.5 m above the linear pipeline (the benchmark flies 1.5 m) in Jerlov
# II water (the benchmark's world uses IB), 30 s, 301 images. Needs a built workspace.
set -eo pipefail
cd "$(dirname "$0")/.."
source install/setup.bash
set -u
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-43}"
unav launch launch_scripts/pipe_inspection.launch.yaml output_dir:="$TMP/train" height:=2.5 duration:=30 \
  scenario:="$PWD/config/scenarios/vslam.yaml" set:="[water=II]" > "$TMP/launch.log" 2>&1 || { tail -20 "$TMP/launch.log"; exit 1; }
install/unav_localization/lib/unav_localization/unav_train_vocabulary --images "$TMP/train/rgb" \
  --out config/vocabulary/orb_vocabulary.bin --features 1000 --branching 10 --levels 4
