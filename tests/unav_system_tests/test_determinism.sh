#!/usr/bin/env bash
# Lockstep runs repeat exactly: the pipe-inspection launch (physics 1 kHz, MPC + allocator +
# waypoint follower, renderer, recorder: seven processes over DDS) is run twice with the same
# seed; the ground truth (a function of every thruster command), the IMU samples and every
# rendered image must be byte-identical. Then a short visual-localisation run (vslam_run: ORB SLAM
# and KLT VO as lockstep participants, evaluator) twice: ground truth and both estimators'
# trajectories byte-identical. Nothing in the loop may read the wall clock (the MPC is bounded by
# iterations only in lockstep), and a run ends on a barrier every participant answered.
source "$(dirname "$0")/common.sh"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; for r in a b va vb; do [ -f "$out/$r.log" ] && { echo "--- run $r:"; tail -15 "$out/$r.log"; }; done; exit 1; }
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
echo "pipe inspection identical: $frames frames, $(grep -vc '^#' "$out/a/groundtruth.txt") poses, $(grep -vc '^#' "$out/a/imu.txt") IMU samples; moved $moved m"
for r in va vb; do
  timeout -s INT 200 unav launch "$ws/launch_scripts/vslam_run.launch.yaml" route:=linear output_dir:="$out/$r" duration:=6 \
    domain:="$ROS_DOMAIN_ID" >"$out/$r.log" 2>&1 || fail "vslam run $r exited with $?"
done
for f in linear_ground_truth.tum linear_orb_slam.tum linear_klt_vo.tum; do
  [ -s "$out/va/$f" ] || fail "vslam run wrote no $f"
  cmp -s "$out/va/$f" "$out/vb/$f" || fail "$f differs between two vslam runs: $(diff "$out/va/$f" "$out/vb/$f" | head -4)"
done
echo "vslam identical: $(wc -l < "$out/va/linear_orb_slam.tum") orb_slam poses, $(wc -l < "$out/va/linear_klt_vo.tum") klt_vo poses"
echo "1 passed, 0 failed"
