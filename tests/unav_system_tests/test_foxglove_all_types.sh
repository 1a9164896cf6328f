#!/usr/bin/env bash
# Every message type of interfaces/ through the live bridge: the fixture bag with two messages of
# each of them (unav_bag's make_fixture_bags, all_types: one topic per type) is played in a loop,
# `unav foxglove` advertises each topic with its ros2msg schema, and a client made of Foxglove's
# own parsers (foxglove_client.mjs all) subscribes to every channel, parses every schema and
# decodes every message: each of the bag's types must arrive and decode. One is left out, and
# must be: rmw_dds_common/ParticipantEntitiesInfo, the ROS 2 graph's own discovery type, which
# every one of our participants registers as a generated type (raw bytes cannot share its name in
# a participant: `unav bag play` and the bridge say so and skip it).
source "$(dirname "$0")/common.sh"
tmp=$(mktemp -d); log="$tmp/play.log"; blog="$tmp/bridge.log"; out="$tmp/all.json"
fail() { echo "FAIL: $*"; echo "--- play:"; tail -10 "$log"; echo "--- bridge:"; tail -10 "$blog"; exit 1; }
make_bags="$ws/build/unav_bag/make_fixture_bags"
[ -x "$make_bags" ] || fail "no $make_bags (the workspace's build with BUILD_TESTING=ON makes it)"
"$make_bags" "$tmp/bags" >/dev/null || fail "make_fixture_bags"
unav bag play --loop "$tmp/bags/all_types" >"$log" 2>&1 &
play_pid=$!
bridge_pid=""
trap 'kill -INT $play_pid $bridge_pid 2>/dev/null || true; wait $play_pid $bridge_pid 2>/dev/null || true; rm -rf "$tmp"' EXIT
start_foxglove_bridge "$blog" || fail "no bridge (above)"
# Wait until the bridge has advertised every topic of the bag (52 types), then decode for 5 s.
want=$(( $(unav bag info "$tmp/bags/all_types" | grep -c "Topic: /all/") - 1 ))
grep -q "'/all/rmw_dds_common/ParticipantEntitiesInfo' not played" "$log" || fail "the graph's own type was played raw"
for _ in $(seq 1 60); do
  n=$(timeout 30 node "$client" "$url" channels 1 2>/dev/null | grep -c '"/all/' || true)
  [ "$n" -ge "$want" ] && break
done
[ "$n" -ge "$want" ] || fail "$n of $want topics advertised"
timeout 60 node "$client" "$url" all 5 >"$out" 2>>"$blog" \
  || fail "a schema or a message did not decode: $(tail -3 "$blog")"
"$py" - "$out" "$want" <<'PY' || fail "decoded: $(head -c 800 "$out")"
import json, sys
r = json.loads(open(sys.argv[1]).read())
want = int(sys.argv[2])
# (The bridge's own <image>/compressed twin of /all/sensor_msgs/Image is not a bag topic: the
# fixture's empty image has no encoding to compress, so it is withdrawn.)
mine = lambda t: t.startswith("/all/") and not t.endswith("/compressed")
decoded = {t: v for t, v in r["decoded"].items() if mine(t)}
silent = [t for t in r["silent"] if mine(t)]
assert len(decoded) == want and not silent, f"{len(decoded)} of {want} decoded; silent: {silent}"
for topic, (schema, count) in decoded.items():
    pkg, typ = topic.split("/")[2:4]
    assert schema == f"{pkg}/msg/{typ}", (topic, schema)
print(f"every type live: {len(decoded)} types decoded by Foxglove's parsers through the bridge")
PY
echo "1 passed, 0 failed"
