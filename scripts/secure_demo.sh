#!/usr/bin/env bash
# The pipe-inspection demo secured end to end with one switch (ROS_SECURITY_ENABLE=true,
# ROS_SECURITY_STRATEGY=Enforce, a keystore made by `unav security`), RUNS times: every node
# authenticates, lockstep delivers every frame (frames = poses) and the evaluation is written; a
# secured observer with its own enclave reads ground truth; a participant without keys, on the
# same domain at the same time, reads nothing.
#
# With Debian 12's Fast DDS 2.9.1, secured participants that discover each other by multicast can
# be left unauthenticated for good when they start together (a race in its SecurityManager, fixed
# upstream in 2.9.2; docs/security.md): secured participants therefore discover by unicast on this
# host. This script counts a launch whose simulated time does not reach the end within 60 s as a
# stall, separately from real failures: 50 of 50 started and finished with UNAV_LAUNCH_STAGGER_MS=0,
# 7 of 30 stalled with ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET (multicast), on the 2-core VM.
#   scripts/secure_demo.sh [RUNS=1] [READERS=both|observer|spy|none]  (which readers join)
set -euo pipefail
trap 'echo "FAIL: unexpected exit at line $LINENO: $BASH_COMMAND"' ERR
ws="$(cd "$(dirname "$0")/.." && pwd)"
runs="${1:-1}"
readers="${2:-both}"
set +u; source "$ws/install/setup.bash"; set -u
source "$ws/tests/unav_system_tests/test_domain.sh"
out=$(mktemp -d)
log="$out/launch.log"
fail() { echo "FAIL: $*"; echo "--- launch log:"; tail -30 "$log"; exit 1; }
cleanup() {
  kill -INT "${launch_pid:-}" "${spy_pid:-}" "${obs_pid:-}" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT

ks="$out/keystore"
unav security create_keystore "$ks" >/dev/null
unav security generate_artifacts -k "$ks" -e /unav/demo -e /unav/observer >/dev/null
[ "$(unav security list_enclaves "$ks" | tr '\n' ' ')" = "/unav/demo /unav/observer " ] || fail "enclaves"
secured() {
  ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce ROS_SECURITY_KEYSTORE="$ks" ROS_SECURITY_ENCLAVE_OVERRIDE="$1" \
    "${@:2}"
}

passed=0 stalled=0
for run in $(seq 1 "$runs"); do
  rm -rf "$out/ds"
  # The demo in the background; the two readers join once its nodes are up.
  secured /unav/demo timeout -s INT 60 unav launch "$ws/launch_scripts/pipe_inspection.launch.yaml" duration:=8.0 \
    output_dir:="$out/ds" >"$log" 2>&1 &
  launch_pid=$!
  for _ in $(seq 1 100); do grep -q "trajectory_evaluator-8\]: process started" "$log" && break; sleep 0.1; done
  sleep 0.5
  obs_cmd=(secured /unav/observer timeout -s INT 60 unav topic echo /rov/ground_truth/odom --once)
  spy_cmd=(timeout -s INT 15 unav topic echo /rov/ground_truth/odom --once)
  case "$readers" in none | spy) obs_cmd=(bash -c 'echo "frame_id: world_ned (observer skipped)"') ;; esac
  case "$readers" in none | observer) spy_cmd=(false) ;; esac
  "${obs_cmd[@]}" >"$out/observer.txt" 2>&1 &
  obs_pid=$!
  sleep 0.3
  "${spy_cmd[@]}" >"$out/spy.txt" 2>&1 &
  spy_pid=$!
  rc=0; wait "$launch_pid" || rc=$?
  launch_pid=
  rc_spy=0; wait "$spy_pid" || rc_spy=$?
  spy_pid=
  [ "$rc_spy" -ne 0 ] || fail "run $run: a participant without keys read ground truth: $(head -5 "$out/spy.txt")"
  grep -q "pose:" "$out/spy.txt" && fail "run $run: the spy printed a message"
  if [ "$rc" -ne 0 ] && grep -q "lockstep: holding at t = 0.000" "$log"; then
    echo "run $run: STALLED (a node pair never matched: $(grep -c 'No key material' "$log" || true) key-material warnings)"
    stalled=$((stalled + 1))
    kill -INT "$obs_pid" 2>/dev/null || true
    wait "$obs_pid" 2>/dev/null || true
    obs_pid=
    continue
  fi
  [ "$rc" -eq 0 ] || fail "run $run: secured demo failed (exit $rc)"
  wait "$obs_pid" || fail "run $run: the secured observer read no ground truth: $(tail -3 "$out/observer.txt")"
  obs_pid=
  grep -q "frame_id: world_ned" "$out/observer.txt" || fail "observer: $(head -5 "$out/observer.txt")"
  frames=$(grep -vc '^#' "$out/ds/rgb.txt")
  poses=$(grep -vc '^#' "$out/ds/groundtruth.txt")
  [ "$frames" -ge 70 ] || fail "run $run: only $frames frames in 8 s of simulated time"
  [ "$poses" -eq "$frames" ] || fail "run $run: $poses poses for $frames frames"
  if ! ls "$out/ds/evaluation" 2>/dev/null | grep -q .; then
    # The same Fast DDS stall on a link outside the lockstep: the evaluator never got an estimate.
    echo "run $run: STALLED link: no evaluation written ($(grep 'trajectory_evaluator-8\] \[' "$log" | tail -1 | sed 's/.*\]: //'))"
    stalled=$((stalled + 1))
    continue
  fi
  echo "run $run: secured demo $frames frames = poses, evaluation written, observer read ground truth, spy nothing"
  passed=$((passed + 1))
done
echo "secure_demo: $passed passed, $stalled stalled (Fast DDS 2.9 handshake), of $runs"
[ "$passed" -gt 0 ]
