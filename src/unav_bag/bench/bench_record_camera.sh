#!/usr/bin/env bash
# Live recording benchmark: the physics server (real time) and the renderer publishing the front
# camera (640x480 rgb8 + depth + segmentation) at 30 Hz, recorded by two `unav bag record -a`
# at once (MCAP and sqlite3) for SECONDS (default 20). Prints, per storage: messages, MB, MB/s,
# queue drops, file size, and the image stream's gaps (frames the renderer stamped that are not
# in the bag). Usage: bench_record_camera.sh WORKSPACE [SECONDS] [STORAGES (default "mcap sqlite3")]
set -euo pipefail
ws="$1"; secs="${2:-20}"; storages="${3:-mcap sqlite3}"
set +u; source "$ws/install/setup.bash"; set -u
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-91} UNAV_SPIN_TIME=3
d=$(mktemp -d)
trap 'kill -INT $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$d"' EXIT
cat >"$d/front.yaml" <<'YAML'
cameras:
  - name: front
    mount: {xyz_m: [0.21, 0.0, 0.05], rpy_deg: [0.0, 0.0, 0.0]}
    width: 640
    height: 480
    hfov_deg: 80.0
    noise_stddev: 0.008
YAML
cat >"$d/bench.launch.yaml" <<YAML
launch:
  - node:
      pkg: unav_physics
      exec: physics_server
      name: physics_server
      namespace: rov
      param:
        - {from: "\$(find-pkg-share unav_resources)/config/physics/physics_server.yaml"}
        - {name: world, value: "$ws/worlds/pipe_inspection/world.yaml"}
        - {name: initial_position, value: "[-1.5, 0.0, 8.35]"}
  - node:
      pkg: unav_renderer
      exec: underwater_renderer
      name: underwater_renderer
      namespace: rov
      param:
        - {name: world, value: "$ws/worlds/pipe_inspection/world.yaml"}
        - {name: rate, value: "30.0"}
        - {name: cameras_config, value: "$d/front.yaml"}
YAML
unav launch "$d/bench.launch.yaml" >"$d/launch.log" 2>&1 &
unav topic list -t | grep -q image || { echo "no image topic"; cat "$d/launch.log"; exit 1; }
pids=()
for b in $storages; do
  unav bag record -a -o "$d/$b" -s "$b" -d "$secs" >"$d/$b.log" 2>&1 &
  pids+=($!)
done
wait "${pids[@]}"
echo "machine: $(nproc) cores, $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}')"
for b in $storages; do
  echo "== $b"
  grep -E "Recorded|image" "$d/$b.log" | sed 's/\[INFO\] \[unav_bag\]: //'
  "$ws/.venv/bin/python" - "$d/$b" "$secs" <<'PY'
import os, sys
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
bag, secs = sys.argv[1], float(sys.argv[2])
ts = get_typestore(Stores.ROS2_HUMBLE)
size = sum(os.path.getsize(os.path.join(bag, f)) for f in os.listdir(bag))
total = 0
with Reader(bag) as r:
    for c in r.connections:
        if c.msgtype != "sensor_msgs/msg/Image":
            continue
        stamps = []
        for conn, t, raw in r.messages(connections=[c]):
            total += len(raw)
            m = ts.deserialize_cdr(raw, conn.msgtype)
            stamps.append(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9)
        gaps = sum(max(0, round((b - a) * 30) - 1) for a, b in zip(stamps, stamps[1:]))
        print(f"  {c.topic}: {len(stamps)} images, {len(stamps) / secs:.1f}/s, {gaps} missing frames (stamp gaps)")
print(f"  image payload {total / 1e6:.1f} MB = {total / 1e6 / secs:.1f} MB/s; folder {size / 1e6:.1f} MB")
PY
done
