#!/usr/bin/env bash
# Two ROVs in one world (pipe_inspection_pair.launch.yaml): one physics server steps the
# scenario's vehicle (/rov) and its fleet vehicle (/rov2), each flown along the pipe by its own
# allocator, MPC and waypoint follower and evaluated on its own: both complete the pipe, each
# within 0.1 m of it on average, on different tracks (rov2 starts 1.2 m to the side); the run
# repeats bit for bit (lockstep waits for both vehicles' commands at every barrier).
source "$(dirname "$0")/common.sh"
out=$(mktemp -d); log="$out/launch.log"
trap 'rm -rf "$out"' EXIT
for run in a b; do
  unav launch "$ws/launch_scripts/pipe_inspection_pair.launch.yaml" output_dir:="$out/$run" duration:=30.0 >"$log" 2>&1 \
    || { echo "FAIL: launch $run"; tail -30 "$log"; exit 1; }
done
"$py" - "$out" <<'PY' || { echo "FAIL: the evaluations"; tail -30 "$log"; exit 1; }
import json, sys
out = sys.argv[1]
def tum(path):
    return [list(map(float, l.split())) for l in open(path) if l.strip() and not l.startswith("#")]
for v in ("rov", "rov2"):
    t = json.load(open(f"{out}/a/{v}/pipe_tracking.json"))
    assert not t["lost"] and t["followed_fraction"] > 0.6, (v, t)  # 30 s of the 21.5 m pipe at the follower's pace
    assert t["mean_e_p_m"] < 0.1, (v, t)
    print(f"{v}: followed {t['followed_fraction']:.2f} of the pipe, mean e_p {t['mean_e_p_m']:.3f} m, max {t['max_e_p_m']:.2f} m")
a, b = tum(f"{out}/a/rov/ground_truth.tum"), tum(f"{out}/a/rov2/ground_truth.tum")
assert len(a) == len(b) == 6001, (len(a), len(b))  # 200 Hz for 30 s, both vehicles at every tick
assert [r[0] for r in a] == [r[0] for r in b]
assert abs(a[0][2] - 0.0) < 1e-9 and abs(b[0][2] - 1.2) < 1e-9, (a[0], b[0])
assert max(abs(x[2] - y[2]) for x, y in zip(a, b)) > 0.5  # two tracks, not one copied
for v in ("rov", "rov2"):
    assert open(f"{out}/a/{v}/ground_truth.tum").read() == open(f"{out}/b/{v}/ground_truth.tum").read(), v
print("two vehicles, two tracks; the second run repeats both bit for bit")
PY
echo "1 passed, 0 failed"
