#!/usr/bin/env bash
# The turbid pipe-inspection demo with sonars (launch_scripts/pipe_inspection_turbid.launch.yaml,
# Jerlov 9C): `unav topic echo` decodes the forward-looking sonar's ProjectedSonarImage and the
# side-scan's RawSonarImage; a bag of them decodes with marine_acoustic_msgs' own definitions
# (check_sonar_bag.py: geometry, 10 Hz of simulated time, the FLS sees the pipe ahead, the
# side-scan sees water column then seabed).
source "$(dirname "$0")/common.sh"
out=$(mktemp -d)
log="$out/launch.log"
fail() { echo "FAIL: $*"; echo "--- launch log:"; tail -30 "$log"; exit 1; }
cleanup() {
  kill -INT "${launch_pid:-}" "${rec_pid:-}" "${echo_pid:-}" "${echo2_pid:-}" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT

# Recorder and echoes first: they subscribe as soon as the sonar's writers appear.
unav bag record /rov/sonar/fls/image /rov/sonar/sidescan/raw -o "$out/bag" \
  >"$out/rec.log" 2>&1 &
rec_pid=$!
timeout -s INT 120 unav topic echo /rov/sonar/fls/image --once >"$out/echo_fls.txt" 2>&1 &
echo_pid=$!
timeout -s INT 120 unav topic echo /rov/sonar/sidescan/raw --once >"$out/echo_ss.txt" 2>&1 &
echo2_pid=$!
sleep 2
unav launch "$ws/launch_scripts/pipe_inspection_turbid.launch.yaml" duration:=8.0 output_dir:="$out/run" \
  >"$log" 2>&1 || fail "turbid demo failed"
launch_pid=
wait "$echo_pid" || fail "no ProjectedSonarImage echoed: $(tail -5 "$out/echo_fls.txt")"
echo_pid=
wait "$echo2_pid" || fail "no RawSonarImage echoed: $(tail -5 "$out/echo_ss.txt")"
echo2_pid=
kill -INT "$rec_pid"
rc=0; wait "$rec_pid" || rc=$?
rec_pid=
[ "$rc" -eq 0 ] || { cat "$out/rec.log"; fail "recorder exit code $rc"; }
grep -q "frame_id: fls_link" "$out/echo_fls.txt" || fail "FLS echo: $(head -20 "$out/echo_fls.txt")"
grep -q "beam_count: 256" "$out/echo_fls.txt" || fail "FLS echo has no beam_count 256"
grep -q "samples_per_beam: 1024" "$out/echo_ss.txt" || fail "side-scan echo: $(head -20 "$out/echo_ss.txt")"
grep -q "sonar.*lockstep" "$log" || fail "the sonar did not run in lockstep"

"$py" "$(dirname "$0")/check_sonar_bag.py" "$out/bag" || fail "sonar bag check"
echo "1 passed, 0 failed"
