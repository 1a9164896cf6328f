#!/usr/bin/env bash
# A live view in Foxglove: `unav foxglove` beside the physics server; a client made of Foxglove's
# own libraries (ws, @foxglove/rosmsg, @foxglove/rosmsg2-serialization:
# src/unav_bag/test/foxglove/live_client.mjs) sees /rov/ground_truth/odom advertised with its
# ros2msg schema, subscribes and decodes 3 odometry messages: frame world_ned, the scenario's start
# (-1.5, 0, ~8.35 m), a unit quaternion. Then Ctrl-C: the bridge exits 0 and says what it sent.
source "$(dirname "$0")/common.sh"
log=$(mktemp); blog=$(mktemp); out=$(mktemp)
fail() { echo "FAIL: $*"; echo "--- launch:"; tail -20 "$log"; echo "--- bridge:"; tail -20 "$blog"; exit 1; }
node_dir="$ws/src/unav_bag/test/foxglove"
[ -d "$node_dir/node_modules/ws" ] || fail "no node_modules/ws in $node_dir (scripts/install_deps.sh runs npm ci)"
unav launch "$ws/launch_scripts/physics.launch.yaml" >"$log" 2>&1 &
launch_pid=$!
port=$((20000 + RANDOM % 20000))
unav foxglove --port "$port" >"$blog" 2>&1 &
bridge_pid=$!
trap 'kill -INT $launch_pid $bridge_pid 2>/dev/null || true; wait $launch_pid $bridge_pid 2>/dev/null || true' EXIT
for _ in $(seq 1 100); do grep -q "Foxglove WebSocket server on" "$blog" && break; sleep 0.1; done
grep -q "ws://127.0.0.1:$port" "$blog" || fail "bridge did not start"
node "$node_dir/live_client.mjs" "ws://127.0.0.1:$port" /rov/ground_truth/odom 3 60 >"$out" 2>>"$blog" \
  || fail "client: $(tail -3 "$blog")"
"$py" - "$out" <<'PY' || fail "decoded odometry: $(head -c 600 "$out")"
import json, math, sys
msgs = [json.loads(l)["message"] for l in open(sys.argv[1])]
assert len(msgs) == 3, len(msgs)
for m in msgs:
    assert m["header"]["frame_id"] == "world_ned" and m["child_frame_id"] == "base_link_frd", m["header"]
    p, q = m["pose"]["pose"]["position"], m["pose"]["pose"]["orientation"]
    assert abs(p["x"] + 1.5) < 0.5 and abs(p["y"]) < 0.5 and 7.5 < p["z"] < 9.5, p
    assert abs(math.sqrt(q["x"]**2 + q["y"]**2 + q["z"]**2 + q["w"]**2) - 1) < 1e-6, q
    assert len(m["pose"]["covariance"]) == 36 and all(math.isfinite(c) for c in m["pose"]["covariance"])
# Foxglove's time type: {sec, nsec}.
stamps = [m["header"]["stamp"]["sec"] + 1e-9 * m["header"]["stamp"]["nsec"] for m in msgs]
assert stamps == sorted(stamps) and stamps[-1] > stamps[0], stamps
print("decoded 3 odometry messages; first position", msgs[0]["pose"]["pose"]["position"])
PY
kill -INT "$bridge_pid"
rc=0; wait "$bridge_pid" || rc=$?
[ "$rc" -eq 0 ] || fail "bridge exit code $rc after SIGINT"
grep -q "messages sent" "$blog" || fail "no summary line"
grep "messages sent" "$blog" | sed 's/^.*\]: //'
echo "1 passed, 0 failed"
