#!/usr/bin/env bash
# The pipe-inspection launch (physics in lockstep, renderer, recorder, VO, SLAM, evaluator): the dataset has one
# ground-truth pose per frame, every rendered frame (10 Hz of simulated time, none skipped),
# every IMU sample (200 Hz), depth in TUM units, and nothing is lost on Ctrl-C.
source "$(dirname "$0")/common.sh"
out=$(mktemp -d)
log="$out/launch.log"
# On failure: every warning and error of the run, ours ("[WARN]") and Fast DDS' ("... Warning]",
# between colour codes), since a lockstep hold's cause is usually said long before the log's
# tail; then the tail.
fail() {
  echo "FAIL: $*"
  echo "--- warnings and errors:"; { grep -E "\[(WARN|ERROR)\]| (Warning|Error)\]" "$log" || true; } | head -60
  echo "--- launch log:"; tail -30 "$log"
  exit 1
}

# Fast DDS' own warnings too (a handful at start-up): if a stream stalls, the middleware's reason
# is in the log (CI once held at t = 2.0 s for 48 s: no rgb frame reached the recorder, the SLAM or
# the VO while the depth and segmentation frames of that instant did).
export UNAV_FASTDDS_LOG=warning
# The SLAM in lockstep: it sees every frame, whatever the machine's load (not in lockstep it
# skipped frames when busy, and a larger step once made it lose track and re-initialise: 23 poses
# of 34 frames, APE 0.14 m).
# The SLAM DVL-aided (the physics server's /rov/dvl and the camera mount on /tf_static): its map
# is scaled to metres after 2 s of keyframes, so its odometry is evaluated without a scale fit too.
unav launch "$ws/launch_scripts/pipe_inspection.launch.yaml" output_dir:="$out/ds" slam_lockstep:=true slam_dvl:=true slam_imu:=true \
  lockstep_participants:="[renderer, recorder, orb_slam]" >"$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true; wait $launch_pid 2>/dev/null || true' EXIT
for _ in $(seq 1 60); do  # until at least 5 s of simulated time are recorded
  n=$(grep -vc '^#' "$out/ds/rgb.txt" 2>/dev/null || true)
  [ "${n:-0}" -ge 51 ] && break
  sleep 1
done
kill -INT "$launch_pid"
rc=0; wait "$launch_pid" || rc=$?
[ "$rc" -eq 130 ] || fail "launch exit code $rc after SIGINT"
frames=$(grep -vc '^#' "$out/ds/rgb.txt")
poses=$(grep -vc '^#' "$out/ds/groundtruth.txt")
depths=$(grep -vc '^#' "$out/ds/depth.txt")
imu=$(grep -vc '^#' "$out/ds/imu.txt")
[ "$frames" -ge 51 ] || fail "only $frames frames"
[ "$poses" -eq "$frames" ] || fail "$poses poses for $frames frames"
[ "$depths" -ge $((frames - 1)) ] || fail "$depths depth images for $frames frames"
# Frames every 0.1 s of simulated time from 0, none skipped (lockstep): last stamp = (n-1)/10.
last=$(tail -1 "$out/ds/rgb.txt" | cut -d' ' -f1)
awk -v t="$last" -v n="$frames" 'BEGIN{exit !((t - (n - 1) * 0.1)^2 < 1e-12)}' || fail "frame stamps skip: last $last for $frames frames"
# IMU at 200 Hz of simulated time with no gap (physics may be one barrier past the last frame).
awk -v t="$last" -v n="$imu" 'BEGIN{exit !(n >= 200 * t - 1 && n <= 200 * (t + 0.1) + 3)}' || fail "$imu IMU samples for $last s"
grep -v '^#' "$out/ds/imu.txt" | awk 'NR > 1 && ($1 - p) > 0.0050001 {print "gap after " p; bad = 1} {p = $1} END {exit bad}' \
  || fail "IMU samples missing"
# The down camera 1.38 m above the sand (vehicle at 8.5 m, camera 0.12 m lower, seabed at 10 m):
# depth at the image centre 1.38 m = 6900 TUM units.
first_depth="$out/ds/$(grep -v '^#' "$out/ds/depth.txt" | head -1 | cut -d' ' -f2)"
[ -s "$first_depth" ] || fail "no depth PNG"
ls "$out/ds/segmentation" | grep -q png || fail "no segmentation PNG"
grep -q "^fx: 160" "$out/ds/camera.yaml" || fail "camera.yaml lacks the intrinsics"
# The monocular ORB SLAM on the 320x180 down camera initialises within the first frames and
# tracks the rest (Sim(3)-aligned), beside the metric RGB-D VO (SE(3)). Seen (DVL-aided): 37 poses
# of 58 frames (odometry from t = 2.2 s, once metric), APE 0.019 m Sim(3) at scale 1.003 and 0.019 m
# SE(3) over ~5.7 s; 10 cm would be a broken map (the pipe is 1.5 m below).
python3 - "$out/ds/evaluation/results.json" "$frames" <<'PY' || fail "estimates out of bounds: $(cat "$out/ds/evaluation/results.md")"
import json, sys
rows = {r["algorithm"]: r for r in json.load(open(sys.argv[1]))}
frames = int(sys.argv[2])
slam, metric, vo = rows["orb_slam"], rows["orb_slam_se3"], rows["klt_vo"]
print("orb_slam: %d poses of %d frames, APE %.4f m (Sim(3), scale %.3f), %.4f m (SE(3), DVL-aided); klt_vo APE %.4f m (SE(3))"
      % (slam["poses"], frames, slam["ape_m"]["rmse"], slam["scale"], metric["ape_m"]["rmse"], vo["ape_m"]["rmse"]))
assert slam["alignment"] == "sim3" and vo["alignment"] == "se3" and metric["alignment"] == "se3"
# DVL-aided, the odometry starts once the map is metric (2 s of keyframes after initialisation).
assert slam["poses"] >= frames - 30, "orb_slam initialised late or lost frames"  # seen: 20-21 missing
assert slam["ape_m"]["rmse"] < 0.1
# Metric: without the DVL the first map's median depth (~1.4 m) is 1 unit, a Sim(3) scale of
# ~1.5 and metres of SE(3) error over the run; scaled at 2 s the SE(3) error stays decimetric.
assert 0.8 < slam["scale"] < 1.25, "orb_slam's map is not in metres"
assert metric["ape_m"]["rmse"] < 0.2
PY
rm -rf "$out"
echo "1 passed, 0 failed"
