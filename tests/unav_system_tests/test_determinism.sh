#!/usr/bin/env bash
# Lockstep runs repeat exactly: the pipe-inspection launch (physics 1 kHz, MPC + allocator +
# waypoint follower, renderer, recorder: seven processes over DDS) is run twice with the same
# seed; the ground truth (a function of every thruster command), the IMU samples and every
# rendered image must be byte-identical. Nothing in the loop may read the wall clock (the MPC is
# bounded by iterations only in lockstep).
set -euo pipefail
trap 'echo "FAIL: unexpected exit at line $LINENO: $BASH_COMMAND"' ERR
ws="$1"
set +u; source "$ws/install/setup.bash"; set -u
source "$(dirname "$0")/test_domain.sh"  # a domain of our own (flock)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; for r in a b; do echo "--- run $r:"; tail -15 "$out/$r.log"; done; exit 1; }
for r in a b; do
  unav launch "$ws/launch_scripts/pipe_inspection.launch.yaml" output_dir:="$out/$r" duration:=4 >"$out/$r.log" 2>&1 \
    || fail "run $r exited with $?"
done
for f in groundtruth.txt imu.txt rgb.txt depth.txt; do
  [ -s "$out/a/$f" ] || fail "run a wrote no $f"
  cmp -s "$out/a/$f" "$out/b/$f" || fail "$f differs between two runs: $(diff "$out/a/$f" "$out/b/$f" | head -4)"
done
frames=$(grep -vc '^#' "$out/a/rgb.txt")
[ "$frames" -ge 40 ] || fail "only $frames frames in 4 s at 10 Hz"
(cd "$out/a" && md5sum rgb/*.png depth/*.png segmentation/*.png) > "$out/a.md5"
(cd "$out/b" && md5sum rgb/*.png depth/*.png segmentation/*.png) > "$out/b.md5"
cmp -s "$out/a.md5" "$out/b.md5" || fail "images differ: $(diff "$out/a.md5" "$out/b.md5" | head -4)"
# The vehicle moved (a test of a vehicle at rest would prove nothing).
moved=$(grep -v '^#' "$out/a/groundtruth.txt" | awk 'NR == 1 {x = $2; y = $3} END {print sqrt(($2 - x)^2 + ($3 - y)^2)}')
awk -v d="$moved" 'BEGIN {exit !(d > 0.3)}' || fail "vehicle moved only $moved m"
echo "identical: $frames frames, $(grep -vc '^#' "$out/a/groundtruth.txt") poses, $(grep -vc '^#' "$out/a/imu.txt") IMU samples; moved $moved m"
echo "1 passed, 0 failed"
