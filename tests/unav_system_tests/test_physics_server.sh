#!/usr/bin/env bash
# physics_server launched as a process: odometry and /clock come out with ROS 2 types, a thruster
# command published by `unav topic pub` moves the vehicle north, the failsafe logs the timeout.
source "$(dirname "$0")/common.sh"
export UNAV_SPIN_TIME=3
log=$(mktemp)
fail() { echo "FAIL: $*"; echo "--- launch log:"; cat "$log"; kill -INT "$launch_pid" 2>/dev/null || true; exit 1; }

unav launch "$ws/launch_scripts/physics.launch.yaml" >"$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true; wait $launch_pid 2>/dev/null || true' EXIT
for line in "/rov/ground_truth/odom [nav_msgs/msg/Odometry]" "/clock [rosgraph_msgs/msg/Clock]" \
  "/rov/imu [sensor_msgs/msg/Imu]"; do
  topics=$(wait_for_topic "$line") || fail "no '$line' in 'unav topic list -t' within 60 s: $topics"
done
north() {  # x of the pose in one odometry message (read whole before parsing: no SIGPIPE)
  local msg
  msg=$(timeout -s INT 20 unav topic echo /rov/ground_truth/odom --once) || fail "no odometry message"
  awk '/position:/{p=1} p&&/ x:/{print $2; exit}' <<<"$msg"
}
x0=$(north)
# Surge: the four horizontal thrusters push forward (north at yaw 0). They sit 8.5 cm below the
# CG, so they also pitch the nose up (0.085 F); the vertical pairs cancel that moment:
# front pair down, rear pair up, each 0.085 * F / (4 * 0.12) = 0.25 of full thrust for
# F = 4 * 0.5 * 0.7071 of full thrust. About 3 s of thrust once the subscription matched.
timeout -s INT 7 unav topic pub /rov/thrusters/command unav_msgs/msg/ThrusterCommand \
  '{u: [0.5, 0.5, -0.5, -0.5, -0.25, -0.25, 0.25, 0.25]}' --rate 20 -w 1 >/dev/null || true
x1=$(north)
awk -v a="$x0" -v b="$x1" 'BEGIN{exit !(b - a > 0.3)}' || fail "vehicle did not move north: x $x0 -> $x1"
sleep 1
grep -q "failsafe" "$log" || fail "no failsafe log after commands stopped"
kill -INT "$launch_pid"
rc=0; wait "$launch_pid" || rc=$?
[ "$rc" -eq 130 ] || fail "launch exit code $rc after SIGINT"
echo "1 passed, 0 failed"
