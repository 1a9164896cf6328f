#!/usr/bin/env bash
# `unav launch` starts talker + listener as two processes; a third process (`unav topic echo`)
# sees their messages; `unav node list` and `topic list -t` show them with ROS 2 names; the
# required listener exits after 150 messages, which ends the launch with exit code 0; and a SIGINT to a second launch stops everything with no orphan left.
source "$(dirname "$0")/common.sh"
export UNAV_SPIN_TIME=3
log=$(mktemp)
fail() { echo "FAIL: $*"; echo "--- launch log:"; cat "$log"; exit 1; }

unav launch "$ws/launch_scripts/talker_listener.launch.yaml" rate:=10.0 count:=150 >"$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true; wait $launch_pid 2>/dev/null || true' EXIT
echo_out=$(timeout -s INT 20 unav topic echo /demo/chatter --once) || fail "topic echo got nothing"
grep -q "^data: 'Hello from UNav-Sim: [0-9]*'$" <<<"$echo_out" || fail "unexpected echo: $echo_out"
nodes=$(unav node list)
grep -qx "/demo/talker" <<<"$nodes" || fail "node list lacks /demo/talker: $nodes"
topics=$(unav topic list -t)
grep -qx "/demo/chatter \[std_msgs/msg/String\]" <<<"$topics" || fail "topic list -t lacks the ROS 2 type: $topics"
wait "$launch_pid" || fail "launch exited non-zero"
grep -q "\[listener-2\].*I heard: 'Hello from UNav-Sim: " "$log" || fail "listener output not prefixed/received"

# Ctrl-C: the launcher forwards SIGINT and leaves no process behind.
unav launch "$ws/launch_scripts/talker_listener.launch.yaml" >"$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true; wait $launch_pid 2>/dev/null || true' EXIT
sleep 3
pids=$(pgrep -P "$launch_pid" || true)
[ -n "$pids" ] || fail "launch started no children"
kill -INT "$launch_pid"
rc=0; wait "$launch_pid" || rc=$?
[ "$rc" -eq 130 ] || fail "launch exit code after SIGINT: $rc (expected 130)"
for p in $pids; do kill -0 "$p" 2>/dev/null && fail "process $p survived the launch"; done
echo "1 passed, 0 failed"
