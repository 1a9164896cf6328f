#!/usr/bin/env bash
# physics + MPC + allocator + waypoint follower as four processes in lockstep: a setpoint 2 m
# north is reached within 10 s of simulated time (position within 5 cm at t = 10 s; the
# in-process tests show < 1 mm steady-state error, 5 cm leaves room for the bounded solver
# iterations over DDS), and the launch ends cleanly when the physics stops.
source "$(dirname "$0")/common.sh"
log=$(mktemp)
rc=0
timeout -s INT 120 unav launch "$ws/launch_scripts/closed_loop.launch.yaml" waypoints:="[2.0, 0.0, 5.0]" \
  initial_position:="[0.0, 0.0, 5.0]" duration:=10.0 >"$log" 2>&1 || rc=$?
fail() { echo "FAIL: $*"; grep -v "Publishing" "$log" | tail -30; exit 1; }
[ "$rc" -eq 0 ] || fail "launch exit code $rc"
line=$(grep "max_sim_time reached" "$log") || fail "physics did not reach t = 10 s"
pos=$(sed 's/.*position NED \[\([^]]*\)\].*/\1/' <<<"$line")
awk -v p="$pos" 'BEGIN{split(p, a, ", "); e = sqrt((a[1]-2)^2 + a[2]^2 + (a[3]-5)^2); print "error at t = 10 s: " e " m"; exit !(e < 0.05)}' \
  || fail "setpoint not reached: $pos"
grep -q "MPC solve failed" "$log" && fail "MPC failures during the run"
echo "1 passed, 0 failed"
