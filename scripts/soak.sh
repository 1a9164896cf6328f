#!/usr/bin/env bash
# Soak run: the turbid pipe-inspection demo with every node (physics, MPC, allocator, follower,
# renderer, sonar, dataset recorder, VO, evaluator) in lockstep, looped over the pipeline for
# MINUTES of wall time. Every 30 s it samples each node's resident memory (/proc/PID/status VmRSS)
# and the simulated time; at the end it checks that no node died, that simulated time kept
# advancing, and that no node's memory grew by more than 20 % between the second sample and the
# last (allocations settle in the first 30 s) — except the trajectory_evaluator, which keeps
# every pose for the APE it computes at shutdown (growth reported, ~1.5 MB per minute). Writes OUT/rss.csv and OUT/summary.txt; exit 1 on
# a failed check. Not a test (an hour is far beyond CI): run it before a release.
#   scripts/soak.sh [MINUTES=60] [OUT=out/soak]
set -euo pipefail
cd "$(dirname "$0")/.."
minutes="${1:-60}"
out="${2:-out/soak}"
set +u; source install/setup.bash; set -u
mkdir -p "$out"
rm -f "$out/rss.csv" "$out/summary.txt"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-77}"
# duration:=0: until stopped; the follower loops (the flight ends over the pipeline's end, so the
# run keeps rendering and pinging there).
unav launch launch_scripts/pipe_inspection_turbid.launch.yaml output_dir:="$out/run" duration:=0 \
  >"$out/launch.log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null || true; wait $launch_pid 2>/dev/null || true' EXIT
sleep 10
nodes=$(grep -o '\[[a-z_]*-[0-9]*\]: process started with pid \[[0-9]*\]' "$out/launch.log" \
  | sed 's/\[\([a-z_]*\)-[0-9]*\]: process started with pid \[\([0-9]*\)\]/\1:\2/')
[ -n "$nodes" ] || { echo "soak: no node started"; tail -20 "$out/launch.log"; exit 1; }
echo "t_s,node,pid,rss_kb,sim_time_s" >"$out/rss.csv"
end=$((SECONDS + minutes * 60))
sample() {
  local sim
  sim=$(timeout 10 unav topic echo /clock --once 2>/dev/null | awk '$1=="sec:"{s=$2} $1=="nanosec:"{printf "%.3f", s + $2 / 1e9; exit}')
  for n in $nodes; do
    local name=${n%%:*} pid=${n##*:} rss
    rss=$(awk '/VmRSS/{print $2}' "/proc/$pid/status" 2>/dev/null || echo dead)
    echo "$SECONDS,$name,$pid,$rss,${sim:-none}" >>"$out/rss.csv"
  done
}
while [ $SECONDS -lt $end ]; do
  sample
  sleep 30
done
sample
{
  echo "soak: $minutes min, $(echo "$nodes" | wc -w) nodes"
  if grep -q ",dead," "$out/rss.csv"; then
    echo "FAIL: a node died: $(grep ',dead,' "$out/rss.csv" | cut -d, -f2 | sort -u | tr '\n' ' ')"
  fi
  first_sim=$(awk -F, 'NR>1 && $5!="none"{print $5; exit}' "$out/rss.csv")
  last_sim=$(awk -F, 'NR>1 && $5!="none"{v=$5} END{print v}' "$out/rss.csv")
  echo "simulated time: ${first_sim:-?} s -> ${last_sim:-?} s"
  if [ -z "$first_sim" ] || awk -v a="$first_sim" -v b="$last_sim" 'BEGIN{exit !(b <= a)}'; then
    echo "FAIL: simulated time did not advance"
  fi
  # Per node: RSS at its second sample and at its last; growth over 20 % fails.
  if ! awk -F, 'NR>1 && $4!="dead" {n[$2]++; if (n[$2]==2) a[$2]=$4; b[$2]=$4}
       END {bad=0; for (k in b) { if (!(k in a)) a[k]=b[k]; g=(b[k]-a[k])/a[k]*100;
            printf "  %-22s %8d kB -> %8d kB (%+.1f %%)\n", k, a[k], b[k], g; if (g>20 && k!="trajectory_evaluator") bad=1 } exit bad}' "$out/rss.csv"; then
    echo "FAIL: memory grew by more than 20 %"
  fi
} | tee "$out/summary.txt"
grep -q FAIL "$out/summary.txt" && exit 1
echo "soak: ok ($out/summary.txt, $out/rss.csv)"
