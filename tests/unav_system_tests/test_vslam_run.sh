#!/usr/bin/env bash
# One short run of the visual-localisation benchmark (launch_scripts/vslam_run.launch.yaml):
# physics (lockstep, waiting for the renderer and the ORB SLAM) + controller + renderer (down
# camera 640 x 480) + orb_slam + orb_slam_aided (DVL + IMU) + orb_slam_vi (IMU) + klt_vo (monocular) + evaluator, 15 s
# of simulated time along the
# linear pipeline. The run must end by itself and leave the Table II files, with the SLAM's
# Sim(3)-aligned APE under 5 cm (seen: ~5 mm) and the KLT VO's under 15 cm.
source "$(dirname "$0")/common.sh"
out=$(mktemp -d)
log="$out/launch.log"
fail() { echo "FAIL: $*"; echo "--- launch log:"; tail -40 "$log"; exit 1; }

rc=0
timeout -s INT 200 unav launch "$ws/launch_scripts/vslam_run.launch.yaml" route:=linear output_dir:="$out/eval" duration:=15 \
  domain:="$ROS_DOMAIN_ID" >"$log" 2>&1 || rc=$?
[ "$rc" -eq 0 ] || fail "launch exit code $rc (the run should stop itself at 15 s)"
for f in results.md results.csv results.json linear_top_view.png linear_ground_truth.tum linear_orb_slam.tum linear_klt_vo.tum rows/linear.tsv; do
  [ -s "$out/eval/$f" ] || fail "missing $f"
done
grep -q "orb_slam.*loops" "$log" || fail "orb_slam printed no summary"
python3 - "$out/eval/results.json" <<'PY' || fail "results out of bounds: $(cat "$out/eval/results.md")"
import json, sys
rows = {r["algorithm"]: r for r in json.load(open(sys.argv[1]))}
slam, aided, klt = rows["orb_slam"], rows["orb_slam_aided"], rows["klt_vo"]
print("orb_slam APE %.4f m (%d poses), klt_vo APE %.4f m (%d poses)" % (slam["ape_m"]["rmse"], slam["poses"], klt["ape_m"]["rmse"], klt["poses"]))
assert slam["trajectory"] == "linear"
assert slam["poses"] >= 120, slam["poses"]      # 150 frames, a few before initialisation
assert slam["ape_m"]["rmse"] < 0.05
# The SLAM aided by the DVL and the IMU: the same map in metres (seen: scale 1.003, APE 2 mm).
print("orb_slam_aided APE %.4f m (%d poses), Sim(3) scale %.4f" % (aided["ape_m"]["rmse"], aided["poses"], aided["scale"]))
assert aided["poses"] >= 120, aided["poses"]
assert aided["ape_m"]["rmse"] < 0.05
assert abs(aided["scale"] - 1.0) < 0.05, aided["scale"]
# The SLAM with the IMU alone (visual-inertial): metric too (seen: scale 0.986, APE 3 mm).
vi = rows["orb_slam_vi"]
print("orb_slam_vi APE %.4f m (%d poses), Sim(3) scale %.4f" % (vi["ape_m"]["rmse"], vi["poses"], vi["scale"]))
assert vi["poses"] >= 120, vi["poses"]
assert vi["ape_m"]["rmse"] < 0.05
assert abs(vi["scale"] - 1.0) < 0.05, vi["scale"]
assert klt["poses"] >= 100
assert klt["ape_m"]["rmse"] < 0.15
PY
rm -rf "$out"
echo "1 passed, 0 failed"
