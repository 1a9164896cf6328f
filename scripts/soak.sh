#!/usr/bin/env bash
# Soak run: the turbid pipe-inspection demo with every node (physics, MPC, allocator, follower,
# renderer, sonar, dataset recorder, VO, evaluator) in lockstep, flying episode after episode over
# the pipeline for MINUTES of wall time: every EPISODE_S seconds (default 60) a new episode starts
# in the same processes (/rov/sim/reset: the vehicle back at the start, at rest; the follower's
# path from its first waypoint; simulated time runs on). Every 30 s it samples each node's resident memory (/proc/PID/status VmRSS),
# its open file descriptors and the simulated time; at the end it checks that no node died, that
# simulated time advanced in every interval (no stuck lockstep barrier), that no node's memory
# grew by more than 5 % between the second sample and the last (allocations settle in the first
# 30 s) — except the trajectory_evaluator, which keeps every pose for the APE it computes at
# shutdown (growth reported, ~1.5 MB per minute) — and that no node's open files grew. Writes OUT/rss.csv and OUT/summary.txt; exit 1 on
# a failed check. Not a test (an hour is far beyond CI): run it before a release.
# Also reported: episodes started, lockstep holds logged, /dev/shm entries before and after.
#   scripts/soak.sh [MINUTES=60] [OUT=out/soak] [EPISODE_S=60]
set -euo pipefail
cd "$(dirname "$0")/.."
minutes="${1:-60}"
out="${2:-out/soak}"
episode_s="${3:-60}"
start_pose='{position: {x: -1.5, y: 0.0, z: 8.35}, orientation: {x: 0.0, y: 0.0, z: 0.0, w: 1.0}}'
shm_before=$(ls /dev/shm | wc -l)
set +u; source install/setup.bash; set -u
mkdir -p "$out"
rm -f "$out/rss.csv" "$out/summary.txt"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-77}"
# duration:=0: until stopped; each episode flies the pipeline from its start.
unav launch launch_scripts/pipe_inspection_turbid.launch.yaml output_dir:="$out/run" duration:=0 \
  >"$out/launch.log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true; wait $launch_pid 2>/dev/null || true' EXIT
sleep 10
nodes=$(grep -o '\[[a-z_]*-[0-9]*\]: process started with pid \[[0-9]*\]' "$out/launch.log" \
  | sed 's/\[\([a-z_]*\)-[0-9]*\]: process started with pid \[\([0-9]*\)\]/\1:\2/')
[ -n "$nodes" ] || { echo "soak: no node started"; tail -20 "$out/launch.log"; exit 1; }
echo "t_s,node,pid,rss_kb,sim_time_s,open_fds" >"$out/rss.csv"
end=$((SECONDS + minutes * 60))
next_episode=$((SECONDS + episode_s))
resets=0
sample() {
  local sim
  sim=$(timeout 10 unav topic echo /clock --once 2>/dev/null | awk '$1=="sec:"{s=$2} $1=="nanosec:"{printf "%.3f", s + $2 / 1e9; exit}')
  for n in $nodes; do
    local name=${n%%:*} pid=${n##*:} rss fds
    rss=$(awk '/VmRSS/{print $2}' "/proc/$pid/status" 2>/dev/null || echo dead)
    fds=$(ls "/proc/$pid/fd" 2>/dev/null | wc -l)
    echo "$SECONDS,$name,$pid,${rss:-dead},${sim:-none},$fds" >>"$out/rss.csv"
  done
}
while [ $SECONDS -lt $end ]; do
  sample
  if [ $SECONDS -ge $next_episode ]; then
    unav topic pub --once -w 1 /rov/sim/reset geometry_msgs/msg/Pose "$start_pose" >/dev/null 2>&1 \
      && resets=$((resets + 1))
    next_episode=$((next_episode + episode_s))
  fi
  sleep 30
done
sample
{
  echo "soak: $minutes min, $(echo "$nodes" | wc -w) nodes"
  episodes=$(grep -c "]: episode [0-9]*: the vehicle is at" "$out/launch.log" || true)
  echo "episodes: $((episodes + 1)) ($resets resets sent, $episodes started)"
  [ "$episodes" -eq "$resets" ] || echo "FAIL: $resets resets sent but $episodes episodes started"
  echo "lockstep holds logged (a participant late by 3 s or more): $(grep -c "lockstep: holding at" "$out/launch.log" || true)"
  echo "/dev/shm entries: $shm_before before, $(ls /dev/shm | wc -l) during the run's last sample"
  if grep -q ",dead," "$out/rss.csv"; then
    echo "FAIL: a node died: $(grep ',dead,' "$out/rss.csv" | cut -d, -f2 | sort -u | tr '\n' ' ')"
  fi
  first_sim=$(awk -F, 'NR>1 && $5!="none"{print $5; exit}' "$out/rss.csv")
  last_sim=$(awk -F, 'NR>1 && $5!="none"{v=$5} END{print v}' "$out/rss.csv")
  echo "simulated time: ${first_sim:-?} s -> ${last_sim:-?} s"
  if [ -z "$first_sim" ] || ! awk -F, 'NR>1 && $2=="physics_server" {if ($5=="none" || (seen && $5<=prev)) bad=1; prev=$5; seen=1}
       END {exit bad}' "$out/rss.csv"; then
    echo "FAIL: simulated time did not advance in every interval (a stuck lockstep barrier?)"
  fi
  # Per node: RSS and open files at its second sample and at its last; RSS growth over 5 % or more
  # open files fail.
  if ! awk -F, 'NR>1 && $4!="dead" {n[$2]++; if (n[$2]==2) {a[$2]=$4; fa[$2]=$6} b[$2]=$4; fb[$2]=$6}
       END {bad=0; printf "  %-22s %10s    %10s  %8s  %s\n", "node", "RSS [kB]", "", "growth", "open fds";
            for (k in b) { if (!(k in a)) {a[k]=b[k]; fa[k]=fb[k]} g=(b[k]-a[k])/a[k]*100;
            printf "  %-22s %10d -> %10d  %+7.1f%%  %d -> %d\n", k, a[k], b[k], g, fa[k], fb[k];
            if ((g>5 && k!="trajectory_evaluator") || fb[k]>fa[k]) bad=1 } exit bad}' "$out/rss.csv"; then
    echo "FAIL: memory grew by more than 5 % or open files grew"
  fi
} | tee "$out/summary.txt"
grep -q FAIL "$out/summary.txt" && exit 1
echo "soak: ok ($out/summary.txt, $out/rss.csv)"
