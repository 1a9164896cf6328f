#!/usr/bin/env bash
# `unav datagen` locally: a bad spec fails before any work naming file/key/value; a sweep of 3
# samples over 2 processes finishes with manifests and a contact sheet; a sample regenerated alone
# (its sonar pings too) is byte-identical (same manifest = same SHA-256 of every file); a rerun after deleting a sample
# regenerates only that one, identically; Ctrl-C leaves finished samples valid and the
# interrupted one as .partial, which the next run replaces.
source "$(dirname "$0")/common.sh"
out=$(mktemp -d)
trap 'kill -INT ${pid:-} 2>/dev/null || true; rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
spec="$out/spec.yaml"
# The shipped spec, small: 6 frames of 160x120 per sample.
shipped_spec "$spec" "s|  frames: .*|  frames: 6|" "s|  width: .*|  width: 160|" "s|  height: .*|  height: 120|"

# Bad input: exit 2, the message names file, key, value and rule; nothing is written.
sed 's|    turbidity: .*|    turbidity: {uniform: [1.6, 0.7]}|' "$spec" >"$out/bad.yaml"
rc=0; msg=$(unav datagen "$out/bad.yaml" -n 2 --out "$out/bad" 2>&1) || rc=$?
[ "$rc" -eq 2 ] || fail "bad spec: exit $rc ($msg)"
grep -q "bad.yaml: world.water.turbidity.uniform = \[1.6, 0.7\]: empty range" <<<"$msg" || fail "bad spec message: $msg"
[ ! -e "$out/bad" ] || fail "bad spec: output folder created"
printf 'seed: 1\nworld: {water: {preset: jerlov_X}}\n' >"$out/bad2.yaml"
msg=$(unav datagen "$out/bad2.yaml" --out "$out/bad" 2>&1) && fail "unknown preset accepted"
grep -q "world.water.preset = jerlov_X: must be one of" <<<"$msg" || fail "unknown preset message: $msg"

# A sweep over two processes.
unav datagen "$spec" -n 3 -j 2 --out "$out/a" --contact-sheet >"$out/a.log" 2>&1 || { cat "$out/a.log"; fail "sweep failed"; }
for i in 0 1 2; do
  m="$out/a/sample_00000$i/manifest.json"
  [ -f "$m" ] || fail "sample $i: no manifest"
  "$ws/.venv/bin/python" - "$m" "$i" <<'PY' || fail "sample $i: manifest content"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["counts"]["images"] == 6 and m["counts"]["depth"] == 6 and m["counts"]["segmentation"] == 6, m["counts"]
assert m["randomization"]["seed"] == 1000 + int(sys.argv[2])
assert m["camera"]["width"] == 160 and m["camera"]["height"] == 120
assert any(f["path"] == "world/scenario.yaml" for f in m["files"])
assert m["source"]["world"] == "world/scenario.yaml"
# The spec pings the forward-looking sonar at 10 Hz: t = 0.0 .. 0.5 s for 6 frames at 10 Hz.
s = m["sonar"]
assert s["name"] == "fls" and s["pings"] == 6 and s["channels"] == 256 and s["bins"] == 512, s
assert len(s["channel_azimuth_rad"]) == 256 and 1400 < s["sound_speed_mps"] < 1600
pngs = [f["path"] for f in m["files"] if f["path"].startswith("sonar/fls/") and f["path"].endswith(".png")]
assert len(pngs) == 6 and "sonar/fls/pings.txt" in [f["path"] for f in m["files"]], pngs
# The navigation sensors as they sampled over the 0.55 s flown: pressure at 50 Hz, DVL at 10 Hz,
# every sample kept. Each frame's body depth (groundtruth_body.txt) against the pressure sample
# nearest in time (<= 10 ms): within 3 cm (20 Pa noise = 2 mm, <= 1 cm of motion in 10 ms).
import math, os
d = os.path.dirname(sys.argv[1])
n = m["nav"]
assert 26 <= n["pressure"]["rows"] <= 29 and 5 <= n["dvl"]["rows"] <= 6, n
rows = lambda f: [[float(v) for v in l.split(",")] for l in open(os.path.join(d, f)) if not l.startswith("#")]
pressure, dvl = rows("nav/pressure.csv"), rows("nav/dvl.csv")
assert len(pressure) == n["pressure"]["rows"] and len(dvl) == n["dvl"]["rows"], (len(pressure), len(dvl))
assert all(b[0] - a[0] > 0.0199 for a, b in zip(pressure, pressure[1:]))  # 50 Hz, none twice
for l in open(os.path.join(d, "groundtruth_body.txt")):
    if l.startswith("#"):
        continue
    t, z = float(l.split()[0]), float(l.split()[3])
    near = min(pressure, key=lambda r: abs(r[0] - t))
    assert abs(near[0] - t) <= 0.0101 and abs(near[3] - z) < 0.03, (t, z, near)
# Over the sand 1-3 m below: bottom lock on all four beams, the altitude in that range.
assert all(r[1] == 1 and r[6] == 4 and 0.5 < r[5] < 6.0 for r in dvl), dvl
assert all(math.isfinite(v) for r in dvl for v in r[7:15]), dvl
PY
done
[ -f "$out/a/contact_sheet.png" ] || fail "no contact sheet"
# Each sample is a scenario (world/scenario.yaml: the base world and the sample's draw of the
# generator): re-flown in process, it starts where the sample's path starts, in the sample's world.
sc="$out/a/sample_000000/world/scenario.yaml"
[ -f "$sc" ] || fail "sample 0: no world/scenario.yaml"
unav run "$sc" --in-process --no-images --out "$out/rerun" >"$out/rerun.log" 2>&1 || { cat "$out/rerun.log"; fail "sample scenario does not run"; }
grep -q "0 MPC failures" "$out/rerun.log" || { cat "$out/rerun.log"; fail "sample scenario: MPC failures"; }
"$ws/.venv/bin/python" - "$out/rerun/scenario.yaml" "$out/rerun/ground_truth.tum" "$out/a/sample_000000/manifest.json" "$ws" <<'PY' || fail "sample scenario content"
import json, os, sys, yaml
s = yaml.safe_load(open(sys.argv[1]))
m = json.load(open(sys.argv[3]))
assert os.path.samefile(s["world"], os.path.join(sys.argv[4], "worlds/pipe_inspection/world.yaml")), s["world"]
assert s["generate"]["enabled"] is True
assert s["generate"]["pipeline"] == m["randomization"]["world"]["pipeline"], (s["generate"], m["randomization"]["world"])
first = [float(v) for v in open(sys.argv[2]).readline().split()[1:4]]
assert all(abs(a - b) < 1e-9 for a, b in zip(first, s["vehicle"]["initial_position"])), (first, s["vehicle"])
assert len(s["mission"]["waypoints"]) >= 1 and abs(s["mission"]["duration_s"] - 0.6) < 1e-9, s["mission"]
PY
grep -q "3 samples, 18 frames" "$out/a.log" || { cat "$out/a.log"; fail "summary line"; }

# Reproducible: sample 1 alone, in another folder, is byte-identical.
unav datagen "$spec" --start 1 -n 1 --out "$out/b" >/dev/null 2>&1 || fail "single sample failed"
cmp -s "$out/a/sample_000001/manifest.json" "$out/b/sample_000001/manifest.json" || fail "sample 1 not reproduced"

# The renderer switches change the shading and nothing else: sample 1 without shadows, caustics
# and materials has the same world, depth, segmentation, sonar and ground truth, other RGB images.
{ cat "$spec"; printf 'render: {shadows: false, caustics: false, materials: false}\n'; } >"$out/flat.yaml"
unav datagen "$out/flat.yaml" --start 1 -n 1 --out "$out/f" >/dev/null 2>&1 || fail "render switches: sample failed"
"$ws/.venv/bin/python" - "$out/b/sample_000001/manifest.json" "$out/f/sample_000001/manifest.json" <<'PY' || fail "render switches"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
switches = ("shadows", "caustics", "materials")
assert all(a["randomization"]["render"][k] is True for k in switches), a["randomization"]["render"]
assert all(b["randomization"]["render"][k] is False for k in switches), b["randomization"]["render"]
fa = {f["path"]: f["sha256"] for f in a["files"]}
fb = {f["path"]: f["sha256"] for f in b["files"]}
assert fa.keys() == fb.keys()
same = [p for p in fa if p.startswith(("depth/", "segmentation/", "sonar/")) or p == "groundtruth.txt"]
assert len(same) >= 12 and all(fa[p] == fb[p] for p in same), [p for p in same if fa[p] != fb[p]]
# The same world drawn.
assert a["randomization"]["world"] == b["randomization"]["world"]
rgb = [p for p in fa if p.startswith("rgb/")]
assert len(rgb) == 6 and sum(fa[p] != fb[p] for p in rgb) == 6, [p for p in rgb if fa[p] == fb[p]]
PY

# Resume: only the deleted sample is generated again, identically.
cp "$out/a/sample_000001/manifest.json" "$out/m1.json"
rm -rf "$out/a/sample_000001"
unav datagen "$spec" -n 3 --out "$out/a" >"$out/resume.log" 2>&1 || { cat "$out/resume.log"; fail "resume failed"; }
grep -q "2 of 3 samples already finished (skipped)" "$out/resume.log" || { cat "$out/resume.log"; fail "resume did not skip"; }
grep -q "1 samples, 6 frames" "$out/resume.log" || { cat "$out/resume.log"; fail "resume did more than one sample"; }
cmp -s "$out/m1.json" "$out/a/sample_000001/manifest.json" || fail "resumed sample differs"

# Ctrl-C during a long sample: exit 130, finished samples kept, the interrupted one is .partial.
sed -i "s|  frames: .*|  frames: 100000|" "$spec"
unav datagen "$spec" -n 2 --out "$out/c" >"$out/c.log" 2>&1 &
pid=$!
for _ in $(seq 1 100); do [ -d "$out/c/.sample_000000.partial/rgb" ] && break; sleep 0.2; done
sleep 1
kill -INT "$pid"
rc=0; wait "$pid" || rc=$?; pid=
[ "$rc" -eq 130 ] || { cat "$out/c.log"; fail "Ctrl-C exit code $rc"; }
[ -d "$out/c/.sample_000000.partial" ] || fail "interrupted sample not left as .partial"
[ ! -e "$out/c/sample_000000" ] || fail "interrupted sample counted as finished"
grep -q "interrupted" "$out/c.log" || fail "no interruption message"
echo "1 passed, 0 failed"
