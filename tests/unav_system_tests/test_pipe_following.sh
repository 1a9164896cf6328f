#!/usr/bin/env bash
# The trained pipe follower flies the paper's evaluation pipe over DDS (physics, renderer,
# drl_planner with the shipped ONNX policy, MPC, allocator, evaluator: six processes in
# lockstep). The evaluator's cross-track figures must meet the issue's target: the whole pipe
# (both turns) followed, mean e_p <= 0.5 m. The classical baseline runs the same launch; its
# figures are printed (a number to beat), and the run must write them.
source "$(dirname "$0")/common.sh"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; for r in drl classical; do [ -f "$out/$r.log" ] && { echo "--- $r:"; tail -15 "$out/$r.log"; }; done; exit 1; }
for policy in drl classical; do
  unav launch "$ws/launch_scripts/pipe_following.launch.yaml" policy:=$policy duration:=45 output_dir:="$out/$policy" \
    >"$out/$policy.log" 2>&1 || fail "$policy run exited with $?"
  [ -s "$out/$policy/evaluation/pipe_tracking.json" ] || fail "$policy: no pipe_tracking.json"
  echo "$policy: $(tr -d '\n ' < "$out/$policy/evaluation/pipe_tracking.json")"
done
python3 - "$out/drl/evaluation/pipe_tracking.json" <<'PY' || fail "the learned policy missed the target"
import json, sys
t = json.load(open(sys.argv[1]))
ok = t["completed"] and not t["lost"] and t["mean_e_p_m"] <= 0.5
print(f"drl: followed {100 * t['followed_fraction']:.0f} % of {t['pipe_length_m']:.1f} m, "
      f"mean e_p {t['mean_e_p_m']:.3f} m, max {t['max_e_p_m']:.3f} m -> {'ok' if ok else 'FAIL'}")
sys.exit(0 if ok else 1)
PY
echo "pipe following over DDS: ok"
