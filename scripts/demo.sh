#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the pipe-inspection demo headless on
# defaults: physics (1 kHz, lockstep) + underwater renderer (front and down cameras) + dataset
# recorder, as separate processes over DDS. Stops after DEMO_SIM_SECONDS of simulated time.
# Then DRL pipe following with the shipped policy (DEMO_DRL=0 skips it) and the visual-localisation
# benchmark (vslam_benchmark.launch.yaml; DEMO_VSLAM=0 skips it).
set -eo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
# Only what the demo runs: no tests, benchmarks or fuzz targets (README command 2 builds those).
bash scripts/build.sh -DBUILD_TESTING=OFF --packages-skip unav_fuzz unav_system_tests
source install/setup.bash
set -u
OUT="${UNAV_OUT:-$PWD/out/demo}"
SIM_SECONDS="${DEMO_SIM_SECONDS:-40}"
rm -rf "$OUT" && mkdir -p "$OUT"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-42}"
echo "demo: pipe inspection, ${SIM_SECONDS} s of simulated time, DDS domain $ROS_DOMAIN_ID (log: $OUT/launch.log)"
# The estimators are lockstep participants here: each sees every frame from the first, so the
# APE figures are the same on every run and machine (else one that subscribes late on a cold start
# misses the first frames: seen on a fresh clone, klt_vo's track began at t = 0.7 s).
unav launch launch_scripts/pipe_inspection.launch.yaml output_dir:="$OUT/dataset" duration:="$SIM_SECONDS" \
  lockstep_participants:="[renderer, recorder, klt_vo, orb_slam]" vo_lockstep:=true slam_lockstep:=true slam_dvl:=true slam_imu:=true \
  > "$OUT/launch.log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true' EXIT
sleep 5
unav topic list -t > "$OUT/topics.txt" || true
rc=0; wait "$launch_pid" || rc=$?
trap - EXIT
[ "$rc" -eq 0 ] || { echo "demo: launch failed (exit $rc); see $OUT/launch.log"; exit 1; }
frames=$(grep -vc '^#' "$OUT/dataset/rgb.txt")
grep -h "path finished\|max_sim_time reached" "$OUT/launch.log" | sed 's/^\[[^]]*\] //' || true
echo "demo: finished: $frames frames of the down camera with depth, segmentation, ground truth and IMU"
echo "demo: outputs in $OUT:"
echo "  dataset/ (TUM RGB-D layout: rgb/ depth/ segmentation/ rgb.txt depth.txt groundtruth.txt imu.txt camera.yaml)"
echo "  dataset/evaluation/ (KLT RGB-D VO (SE(3)) and the ORB SLAM aided by the DVL and the IMU, Sim(3) and without a scale fit (orb_slam_se3), vs ground truth: results.md/csv/json, TUM files, top_view.png)"
echo "  launch.log (all node output), topics.txt (the ROS 2 topics that were live)"
if [ -f "$OUT/dataset/evaluation/results.md" ]; then grep "^|" "$OUT/dataset/evaluation/results.md"; fi

# Second part: DRL pipe following (the paper's section V-B): the shipped policy flies the pipe from
# the down camera over DDS; the evaluator scores the cross-track error. About 15 s; DEMO_DRL=0 skips it.
if [ "${DEMO_DRL:-1}" != "0" ]; then
  echo "demo: DRL pipe following, learned policy (log: $OUT/pipe_following.log)"
  rc=0
  unav launch launch_scripts/pipe_following.launch.yaml output_dir:="$OUT/pipe_following" > "$OUT/pipe_following.log" 2>&1 || rc=$?
  [ "$rc" -eq 0 ] || { echo "demo: pipe following failed (exit $rc); see $OUT/pipe_following.log"; exit 1; }
  grep -h "pipe tracking" "$OUT/pipe_following.log" | sed 's/^.*\]: //' || true
  echo "demo: outputs in $OUT/pipe_following/evaluation: pipe_tracking.json (cross-track error e_p, length followed), ground_truth.tum, top_view.png"
fi

# Third part: the visual-localisation benchmark (the paper's Table II): the linear and the loop
# pipeline flown at once, monocular ORB SLAM + KLT VO on the 640x480 down camera, evaluated.
# About 2 minutes on 2 cores; DEMO_VSLAM=0 skips it.
if [ "${DEMO_VSLAM:-1}" != "0" ]; then
  echo "demo: visual localisation benchmark (linear 40 s + loop 66 s of simulated time, log: $OUT/vslam.log)"
  rc=0
  unav launch launch_scripts/vslam_benchmark.launch.yaml output_dir:="$OUT/vslam" > "$OUT/vslam.log" 2>&1 || rc=$?
  [ "$rc" -eq 0 ] || { echo "demo: vslam benchmark failed (exit $rc); see $OUT/vslam.log"; exit 1; }
  echo "demo: outputs in $OUT/vslam: results.md/csv/json (APE/RPE, Sim(3)-aligned), <run>_top_view.png, TUM files"
  [ -f "$OUT/vslam/results.md" ] && head -6 "$OUT/vslam/results.md"
fi
exit 0
