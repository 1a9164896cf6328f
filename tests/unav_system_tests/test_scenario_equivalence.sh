#!/usr/bin/env bash
# One scenario, two paths (DESIGN.md section 9), bit for bit: the same scenario file flown in
# process (`unav run --in-process`: the Episode) and as five processes over DDS in lockstep
# (launch_scripts/scenario.launch.yaml: physics_server, mpc_controller with setpoint_sync,
# control_allocator, underwater_renderer and scenario_mission, each given scenario:=) must write
# the same ground_truth.tum (every control instant, the pose to 17 significant digits) and the same
# PNG of every camera frame, byte for byte. Why bit for bit and not "close": both paths build the
# plant, MPC, allocator and renderer from the one scenario through the same code, the nodes see
# exactly the doubles the Episode sees (odometry carries them unchanged; the Episode's clock is the
# stamp's nanoseconds, as the nodes read it), and nothing reads the wall clock (solves bounded by
# iterations). A different plant, a missing seabed, a skipped control period, another noise seed
# or one ulp of time shows as a difference.
#  1. config/scenarios/pipe_inspection.yaml, the first 10 s of its mission (both cameras, 10 Hz).
#  2. Seabed contact with saturated thrusters, in a world the scenario generates (`generate:`, built
#     by each node and the Episode from the scenario: a different world in one of them shows in the
#     images and the contact): the same vehicle driven at 2 m/s towards a point 2 m below the
#     seabed (10 m +- 0.15 m relief), 2.2 m aside and turned by 90 deg, stops on it in both paths: its bottom (z + 0.127 m)
#     ends within the relief plus <= 0.1 m of penalty spring (2000 N/m against at most the
#     vertical thrusters' force), not moving vertically by more than 5 mm in the last second (it
#     pushes and slides on the sand). The allocator saturates (surge, sway and yaw at once: >= 100
#     of the 200 commands, scaled down to 0.55 and less; a straight dive alone stays within the
#     thrusters' box since the MPC's Jacobians are analytic), so the achieved
#     wrench's way back to the MPC (control/wrench_achieved; Mpc::SetAppliedWrench in process) is
#     exercised: the DDS log must show it.
source "$(dirname "$0")/common.sh"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# run_both NAME SCENARIO: both paths into $out/NAME/{inproc,dds}; fails unless every file matches.
run_both() {
  local name="$1" scenario="$2" d="$out/$1"
  mkdir -p "$d"
  log="$d/inproc.log"
  unav run "$scenario" --in-process --out "$d/inproc" > "$log" 2>&1 || { tail -20 "$log"; fail "$name: unav run --in-process failed"; }
  log="$d/launch.log"
  local rc=0
  timeout -s INT 180 unav launch "$ws/launch_scripts/scenario.launch.yaml" scenario:="$scenario" duration:=10.0 \
    output_dir:="$d/dds" > "$log" 2>&1 || rc=$?
  [ "$rc" -eq 0 ] || { tail -30 "$log"; fail "$name: launch exit code $rc"; }
  grep -q "MPC solve failed" "$log" && fail "$name: MPC failures over DDS"
  local a="$d/inproc/ground_truth.tum" b="$d/dds/ground_truth.tum"
  [ "$(wc -l < "$a")" -eq 201 ] || fail "$name: in process $(wc -l < "$a") poses, expected 201"
  if ! cmp -s "$a" "$b"; then
    paste -d' ' "$a" "$b" | awk '{ d = sqrt(($2-$10)^2 + ($3-$11)^2 + ($4-$12)^2); if (d > m) { m = d; t = $1 } }
      END { printf "max position difference %.3g m (t = %s s)\n", m, t }'
    fail "$name: the ground truths differ"
  fi
  local frames differ
  frames=$(find "$d/inproc" -name '*.png' | wc -l)
  [ "$frames" -eq 202 ] || fail "$name: in process $frames frames, expected 202 (2 cameras, 0..10 s at 10 Hz)"
  differ=$(diff -rq -x scenario.yaml "$d/inproc" "$d/dds" | wc -l)
  [ "$differ" -eq 0 ] || { diff -rq -x scenario.yaml "$d/inproc" "$d/dds" | head -5; fail "$name: $differ files differ"; }
  echo "$name: ground truth (201 poses) and $frames frames identical in process and over DDS"
}

# 1. The shipped scenario, its mission cut to 10 s, its world path made absolute.
sed -e 's/^  duration_s: .*/  duration_s: 10.0/' -e "s|^world: worlds|world: $ws/worlds|" \
  "$ws/config/scenarios/pipe_inspection.yaml" > "$out/pipe.yaml"
run_both pipe "$out/pipe.yaml"
# The flight moved: 10 s along the mission's first legs (not a hold that would match trivially).
awk 'END { exit !($2 > 2.0) }' "$out/pipe/inproc/ground_truth.tum" || fail "the vehicle did not fly the mission"

# 2. Seabed contact in a generated world: one waypoint 2 m below the seabed, 2.2 m away and turned by
# 90 deg, at 2 m/s: surge, sway and yaw all at once on the horizontal thrusters saturate them.
sed -n '/^mission:/q;p' "$out/pipe.yaml" | sed 's/^name: .*/name: seabed_contact/' > "$out/contact.yaml"
cat >> "$out/contact.yaml" <<'YAML'
generate:
  enabled: true
  pipeline: {heading_deg: 60, first_length_m: 6, legs: [{turn_deg: -45, length_m: 5}], radius_m: 0.3}
  seabed: {depth_m: 10.0, relief_m: 0.15, relief_wavelength_m: 4.0}
  rocks: {per_100m2: 5}
  water: {preset: 3C}
mission:
  duration_s: 10.0
  speed_mps: 2.0
  waypoints:
    - {position: [-2.0, 1.0, 12.0], yaw_deg: 90.0, hold_s: 10.0}
YAML
run_both contact "$out/contact.yaml"
grep -q "wrench saturates the thrusters" "$out/contact/launch.log" || fail "contact: the thrusters never saturated"
awk '{ z[NR] = $4 } END {
  bottom = z[NR] + 0.127
  printf "contact: bottom at %.4f m (seabed 10 m +- 0.15 m), moved %.2g m in the last second\n", bottom, z[NR] - z[NR-20]
  exit !(bottom > 9.85 && bottom < 10.25 && (z[NR] - z[NR-20])^2 < 25e-6) }' "$out/contact/inproc/ground_truth.tum" \
  || fail "the vehicle did not stop on the seabed"
echo "1 passed, 0 failed"
