#!/usr/bin/env bash
# Fly the ROV from Foxglove: teleop.launch.yaml (physics, allocator, MPC, cameras, sonar in real
# time) and `unav foxglove`; a client made of Foxglove's own libraries
# (src/unav_bag/test/foxglove/foxglove_client.mjs: @foxglove/ws-protocol, rosmsg2-serialization,
# rosmsg-msgs-common) checks that
#  - every topic docs/foxglove/unav_layout.json shows is advertised (the setpoint it publishes
#    and the estimators' paths, which pipe_inspection.launch.yaml adds, aside),
#  - the odometry decodes to the scenario's start, in Foxglove's time type,
#  - every advertised schema parses and every message of every channel decodes (4 s of all),
#  - the front camera arrives compressed (whole JPEG frames, compressed_image_transport's format),
#  - setpoints it publishes as PoseStamped (geometry_msgs/PoseStamped of ROS 2 Humble, as the
#    Publish panel writes them) reach the MPC: the vehicle moves >= 1 m towards a point 3 m ahead;
# then Ctrl-C: the bridge exits 0 and counts what clients sent; a secured bridge is refused unless
# --allow-secured.
source "$(dirname "$0")/common.sh"
log=$(mktemp); blog=$(mktemp); out=$(mktemp); tmp=$(mktemp -d)
fail() { echo "FAIL: $*"; echo "--- launch:"; tail -20 "$log"; echo "--- bridge:"; tail -20 "$blog"; exit 1; }
unav launch "$ws/launch_scripts/teleop.launch.yaml" >"$log" 2>&1 &
launch_pid=$!
bridge_pid=""
trap 'kill -INT $launch_pid $bridge_pid 2>/dev/null || true; wait $launch_pid $bridge_pid 2>/dev/null || true; rm -rf "$tmp"' EXIT
start_foxglove_bridge "$blog" || fail "no bridge (above)"

# 1. The layout's topics: wait until the last node's (the sonar's fan) is advertised.
for _ in $(seq 1 60); do
  node "$client" "$url" channels 1 >"$out" 2>>"$blog" || fail "channels"
  grep -q '"/rov/sonar/fls/image_fan"' "$out" && grep -q '"/rov/camera/front/image_raw/compressed"' "$out" && break
done
"$py" - "$ws/docs/foxglove/unav_layout.json" "$out" <<'PY' || fail "layout topics"
import json, sys
layout = json.load(open(sys.argv[1]))
advertised = {json.loads(l)["topic"] for l in open(sys.argv[2])}
shown = set()
def walk(v):
    if isinstance(v, dict):
        for k, x in v.items():
            if k in ("imageTopic", "calibrationTopic", "topicPath") and isinstance(x, str): shown.add(x)
            elif k == "value" and isinstance(x, str) and x.startswith("/"): shown.add(x.split(".")[0])
            elif k == "topics" and isinstance(x, dict): shown.update(x)
            else: walk(x)
    elif isinstance(v, list):
        for x in v: walk(x)
walk(layout["configById"])
published = {layout["configById"]["3D!scene"]["publish"]["poseTopic"]}
elsewhere = {"/rov/localization/orb_slam/path", "/rov/localization/klt_vo/path"}  # pipe_inspection's estimators
missing = sorted(shown - advertised - elsewhere)
assert not missing, f"layout topics not advertised: {missing}"
assert published == {"/rov/control/pose_setpoint"}, published
print(f"layout: {len(shown)} topics shown, {len(shown & advertised)} advertised, {sorted(shown & elsewhere)} from the estimators")
PY

# 2. The odometry, decoded: the frames, the scenario's start (-1.5, 0, ~8.35 m), a unit
#    quaternion, Foxglove's time type {sec, nsec}, stamps that advance.
node "$client" "$url" echo /rov/ground_truth/odom 3 >"$out" 2>>"$blog" || fail "echo odometry"
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
stamps = [m["header"]["stamp"]["sec"] + 1e-9 * m["header"]["stamp"]["nsec"] for m in msgs]
assert stamps == sorted(stamps) and stamps[-1] > stamps[0], stamps
print("odometry: 3 messages decoded; first position", msgs[0]["pose"]["pose"]["position"])
PY

# 3. Every channel: its schema parses and every message decodes with Foxglove's parsers.
node "$client" "$url" all 4 >"$out" 2>>"$blog" || fail "all channels"
"$py" - "$out" <<'PY' || fail "decoded: $(cat "$out")"
import json, sys
r = json.loads(open(sys.argv[1]).read())
types = {t for t, n in r["decoded"].values()}
need = {"nav_msgs/msg/Odometry", "nav_msgs/msg/Path", "sensor_msgs/msg/Imu", "unav_msgs/msg/Dvl",
        "tf2_msgs/msg/TFMessage", "std_msgs/msg/String", "sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage",
        "sensor_msgs/msg/CameraInfo", "marine_acoustic_msgs/msg/ProjectedSonarImage", "unav_msgs/msg/ThrusterState",
        "rosgraph_msgs/msg/Clock", "unav_msgs/msg/UsblFix", "sensor_msgs/msg/FluidPressure"}
assert need <= types, f"not decoded: {sorted(need - types)}; silent: {r['silent']}"
print(f"all channels: {len(r['decoded'])} decoded ({len(types)} types), silent: {r['silent']}")
PY

# 4. The front camera, compressed on request.
node "$client" "$url" measure /rov/camera/front/image_raw/compressed 3 >"$out" 2>>"$blog" || fail "compressed camera"
"$py" - "$out" <<'PY' || fail "compressed frames: $(cat "$out")"
import json, sys
r = json.loads(open(sys.argv[1]).read())
assert r["formats"] == ["rgb8; jpeg compressed bgr8"], r
assert r["frames"] >= 2 and 2000 < r["bytes_per_frame"] < 640 * 480 * 3 / 4, r  # a JPEG, far below raw
print(f"compressed front camera: {r['frames']} frames, {r['bytes_per_frame']} bytes each, {r['fps']} frames/s")
PY

# 5. Teleop: setpoints published by the client fly the vehicle.
node "$client" "$url" teleop /rov/control/pose_setpoint /rov/ground_truth/odom 3 0 0 1.0 90 >"$out" 2>>"$blog" \
  || fail "teleop: $(cat "$out")"
"$py" - "$out" <<'PY' || fail "teleop result: $(cat "$out")"
import json, sys
r = json.loads(open(sys.argv[1]).read())
assert r["moved"] >= 1.0 and r["sent"] >= 1, r
assert abs(r["now"]["y"] - r["start"]["y"]) < 0.5 and abs(r["now"]["z"] - r["start"]["z"]) < 0.5, r  # along x only
print(f"teleop: moved {r['moved']:.2f} m towards the setpoint after {r['sent']} setpoints")
PY
grep -q "a client publishes '/rov/control/pose_setpoint' \[geometry_msgs/msg/PoseStamped\]" "$blog" || fail "no publish line"

kill -INT "$bridge_pid"
rc=0; wait "$bridge_pid" || rc=$?
[ "$rc" -eq 0 ] || fail "bridge exit code $rc after SIGINT"
grep -Eq "messages sent, [0-9]+ dropped .*, [1-9][0-9]* received from clients" "$blog" || fail "summary: $(tail -1 "$blog")"
grep "messages sent" "$blog" | sed 's/^.*\]: //'

# 6. A secured participant is not bridged without --allow-secured.
unav security create_keystore "$tmp/ks" >/dev/null
unav security create_enclave "$tmp/ks" /bridge >/dev/null
rc=0
ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce ROS_SECURITY_KEYSTORE="$tmp/ks" ROS_SECURITY_ENCLAVE_OVERRIDE=/bridge \
  unav foxglove --port 0 >"$out" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || fail "secured bridge: exit $rc, $(cat "$out")"
grep -q "is secured (enclave '/bridge').*--allow-secured" "$out" || fail "secured refusal: $(cat "$out")"
echo "secured: refused without --allow-secured"
echo "1 passed, 0 failed"
