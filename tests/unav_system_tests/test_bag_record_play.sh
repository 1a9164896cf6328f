#!/usr/bin/env bash
# `unav bag record | info | play` against the running physics server: two recorders (MCAP with
# zstd chunks, stopped by Ctrl-C; sqlite3, stopped by --duration) record every topic; the bags
# are read back and decoded by rosbags and mcap-ros2-support (check_bag.py), `unav bag info`
# agrees with them, and `unav bag play` republishes the odometry and /clock with the bag's time.
source "$(dirname "$0")/common.sh"
export UNAV_SPIN_TIME=3
out=$(mktemp -d)
log="$out/launch.log"
fail() { echo "FAIL: $*"; echo "--- launch log:"; tail -20 "$log"; exit 1; }
cleanup() {
  kill -INT "${launch_pid:-}" "${rec_pid:-}" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT

unav launch "$ws/launch_scripts/physics.launch.yaml" >"$log" 2>&1 &
launch_pid=$!
wait_for_topic "/rov/ground_truth/odom [nav_msgs/msg/Odometry]" >/dev/null || fail "physics server not up within 60 s"

unav bag record -a -o "$out/mcap" --compression zstd >"$out/rec_mcap.log" 2>&1 &
rec_pid=$!
unav bag record /rov/ground_truth/odom /tf /clock /rov/imu -o "$out/sqlite" -s sqlite3 -d 5 >"$out/rec_sqlite.log" 2>&1 \
  || { cat "$out/rec_sqlite.log"; fail "sqlite3 recorder failed"; }
kill -INT "$rec_pid"
rc=0; wait "$rec_pid" || rc=$?
[ "$rc" -eq 0 ] || { cat "$out/rec_mcap.log"; fail "mcap recorder exit code $rc after Ctrl-C"; }
rec_pid=
kill -INT "$launch_pid"; wait "$launch_pid" || true; launch_pid=
grep -q "dropped 0;" "$out/rec_mcap.log" || { cat "$out/rec_mcap.log"; fail "mcap recorder dropped messages"; }

# Realtime physics: odometry at >= 50 Hz, IMU at >= 100 Hz (config/physics), so 5 s of
# recording after discovery holds at least 2 s of each at half those rates.
for b in mcap sqlite; do
  [ -f "$out/$b/metadata.yaml" ] || fail "$b: no metadata.yaml"
  "$py" "$(dirname "$0")/check_bag.py" "$out/$b" /rov/ground_truth/odom:50 /tf:50 /clock:50 /rov/imu:100 \
    >"$out/check_$b.txt" 2>&1 || { cat "$out/check_$b.txt"; fail "$b bag does not read back"; }
  info=$(unav bag info "$out/$b")
  while read -r topic n; do
    [ "$topic" = odom_x ] && continue
    grep -q "Topic: $topic | Type: [a-z_0-9/A-Z]* | Count: $n |" <<<"$info" \
      || { echo "$info"; fail "$b: unav bag info disagrees with rosbags on $topic ($n)"; }
  done <"$out/check_$b.txt"
done
grep -q "Storage id:        mcap" <<<"$(unav bag info "$out/mcap")" || fail "info: storage id"

# Play the odometry back (with /clock from the bag's time) and receive it.
first_x=$(awk '/^odom_x/{print $2}' "$out/check_mcap.txt")
timeout -s INT 30 unav topic echo /rov/ground_truth/odom --once >"$out/echo.txt" 2>&1 &
echo_pid=$!
timeout -s INT 30 unav topic echo /clock --once >"$out/clock.txt" 2>&1 &
clock_pid=$!
sleep 2
unav bag play "$out/mcap" --topics /rov/ground_truth/odom --clock 50 -d 3 >"$out/play.log" 2>&1 \
  || { cat "$out/play.log"; fail "play failed"; }
wait "$echo_pid" || { cat "$out/echo.txt"; fail "no odometry received from play"; }
wait "$clock_pid" || { cat "$out/clock.txt"; fail "no /clock received from play"; }
grep -q "child_frame_id" "$out/echo.txt" || fail "played odometry not decoded: $(cat "$out/echo.txt")"
sec=$(awk '/sec:/{print $2; exit}' "$out/clock.txt")
start=$(awk '/Start:/{gsub(/[()]/,"",$NF); split($NF,a,"."); print a[1]; exit}' <<<"$(unav bag info "$out/mcap")")
[ "$sec" -ge "$start" ] || fail "/clock $sec s is before the bag start $start s"
n_played=$(grep -o "Published [0-9]*" "$out/play.log" | awk '{print $2}')
n_odom=$(awk '$1=="/rov/ground_truth/odom"{print $2}' "$out/check_mcap.txt")
[ "$n_played" = "$n_odom" ] || fail "played $n_played of $n_odom odometry messages"
echo "first recorded x $first_x; played $n_played"
echo "1 passed, 0 failed"
