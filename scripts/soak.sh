#!/usr/bin/env bash
# Soak run, two phases sharing the wall time (a script, not a test: an hour is far beyond CI):
#
# 1. Episodes back to back: launch, fly, evaluate, shut down, next. Episode N is draw N of
#    config/scenarios/pipe_inspection_random.yaml (water, start pose, realism switches) flown by the
#    whole pipe-inspection system (physics, MPC, allocator, follower, renderer, recorder, klt_vo,
#    orb_slam, evaluator) for EPISODE_SIM_S simulated seconds. Each episode must finish by itself
#    (exit 0 within a generous timeout: a stalled lockstep is a failure), write as many frames as
#    poses (nothing lost), give the klt_vo a finite APE, and leave /dev/shm as it found it (no
#    data-sharing pool left behind). Per episode: episodes.csv (exit, wall, real-time factor,
#    frames, poses, APEs, /dev/shm) and episode_rss.csv (every process's max RSS and CPU from the
#    launch's resource table); the median max RSS of each process over the last 5 episodes must be
#    within 15 % of the first 5 (a resource that outlives processes: files, shared memory, caches).
# 2. One long-lived system: the turbid demo (the above plus the sonar, all in lockstep) with a new
#    episode every EPISODE_S seconds in the same processes (/rov/sim/reset) and the renderer killed
#    with SIGKILL every RESPAWN_S seconds (launched to respawn: it rejoins the lockstep). Every 30 s
#    each process's RSS, open files and the simulated time go to long_rss.csv; it fails on a dead
#    node, simulated time that did not advance in an interval (a stuck barrier), a renderer not
#    respawned, RSS growth over 5 % from a process's second sample to its last (the evaluator,
#    which keeps every pose for its APE, is only reported), open files growing, a frame missing or
#    written twice (stamps on the camera's 0.1 s grid, one pose per frame) or /dev/shm not back to
#    its start after the launch is stopped.
# Writes OUT/summary.txt; exit 1 on any failed check.
#   scripts/soak.sh [MINUTES=60] [OUT=out/soak]
#   environment: SOAK_PHASES="episodes long" (either or both), EPISODES_SHARE=50 (% of the time
#   for phase 1 when both run), EPISODE_SIM_S=20, EPISODE_S=60, RESPAWN_S=180
set -euo pipefail
cd "$(dirname "$0")/.."
minutes="${1:-60}"
out="${2:-out/soak}"
phases="${SOAK_PHASES:-episodes long}"
share="${EPISODES_SHARE:-50}"
episode_sim_s="${EPISODE_SIM_S:-20}"
episode_s="${EPISODE_S:-60}"
respawn_s="${RESPAWN_S:-180}"
set +u; source install/setup.bash; set -u
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-77}"
mkdir -p "$out"
rm -rf "$out/episodes" "$out/long"
: >"$out/summary.txt"
say() { echo "$*" | tee -a "$out/summary.txt"; }
shm_segments() { find /dev/shm -maxdepth 1 -name 'fast_datasharing_*' 2>/dev/null | wc -l; }
shm_mb() { find /dev/shm -maxdepth 1 -name 'fast_datasharing_*' -printf '%s\n' 2>/dev/null | awk '{s += $1} END {printf "%.1f", s / 1e6}'; }
total_s=$((minutes * 60))
case "$phases" in
  *episodes*long* | *long*episodes*) episodes_s=$((total_s * share / 100)); long_s=$((total_s - episodes_s)) ;;
  *episodes*) episodes_s=$total_s; long_s=0 ;;
  *long*) episodes_s=0; long_s=$total_s ;;
  *) echo "soak: SOAK_PHASES='$phases': expected 'episodes', 'long' or both"; exit 2 ;;
esac

# ---- 1. episodes back to back ----
if [ "$episodes_s" -gt 0 ]; then
  mkdir -p "$out/episodes"
  echo "episode,seed,exit,wall_s,rtf,frames,poses,klt_ape_m,orb_ape_m,orb_poses,shm_segments,shm_mb" >"$out/episodes.csv"
  echo "episode,process,max_rss_mib,cpu_s" >"$out/episode_rss.csv"
  shm0=$(shm_segments)
  ape() { awk -F, -v a="$1" -v c="$2" '$2==a {print $c}' "$dir/evaluation/results.csv" 2>/dev/null || true; }
  end=$((SECONDS + episodes_s))
  i=0
  while [ $SECONDS -lt $end ]; do
    dir="$out/episodes/$i"
    log="$out/episodes/$i.log"
    t0=$SECONDS
    rc=0
    timeout --signal=INT --kill-after=30 $((10 * episode_sim_s + 60)) \
      unav launch launch_scripts/pipe_inspection.launch.yaml \
      scenario:=config/scenarios/pipe_inspection_random.yaml seed:=$i duration:="$episode_sim_s" \
      output_dir:="$dir" >"$log" 2>&1 || rc=$?
    frames=$(grep -vc '^#' "$dir/rgb.txt" 2>/dev/null || true)
    poses=$(grep -vc '^#' "$dir/groundtruth.txt" 2>/dev/null || true)
    rtf=$(grep -o '([0-9.]*x real time)' "$log" | head -1 | tr -dc '0-9.' || true)
    echo "$i,$i,$rc,$((SECONDS - t0)),${rtf:-nan},${frames:-0},${poses:-0},$(ape klt_vo 3),$(ape orb_slam 3),$(ape orb_slam 7),$(shm_segments),$(shm_mb)" \
      >>"$out/episodes.csv"
    awk -v e="$i" '/^  [a-z_]+-[0-9]+ +cpu/ {n = $1; sub(/-[0-9]+$/, "", n); print e "," n "," $(NF - 1) "," $3}' "$log" \
      >>"$out/episode_rss.csv"
    # Keep the folders of failed episodes only (a passing one is ~20 MB of images).
    if [ "$rc" -eq 0 ] && [ "${frames:-0}" -gt 0 ] && [ "$frames" = "$poses" ]; then rm -rf "$dir"; fi
    i=$((i + 1))
  done
  say "episodes: $i in $episodes_s s (draws 0-$((i - 1)) of pipe_inspection_random.yaml, $episode_sim_s s simulated each)"
  awk -F, -v shm0="$shm0" 'NR > 1 {
      n++; if ($3 != 0) {bad++; print "FAIL: episode " $1 " exited " $3 ($3 == 124 ? " (timeout: stalled)" : "")}
      else if ($6 == 0 || $6 != $7) {bad++; print "FAIL: episode " $1 ": " $6 " frames, " $7 " poses"}
      else if ($8 == "" || $8 == "nan" || $8 == "inf") {bad++; print "FAIL: episode " $1 ": klt_vo APE " $8}
      if ($11 > shm0) {bad++; print "FAIL: episode " $1 " left " $11 - shm0 " data-sharing segments in /dev/shm (" $12 " MB)"}
      if ($5 != "nan") {r[++nr] = $5} if ($9 != "" && $9 != "nan") {o[++no] = $9}
      fin += ($3 == 0) }
    function med(a, m,   i, j, t) {for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (a[j] < a[i]) {t = a[i]; a[i] = a[j]; a[j] = t}
      return m ? a[int((m + 1) / 2)] : "nan"}
    END {printf "  finished %d of %d; real-time factor median %s; orb_slam evaluated in %d; failures %d\n", fin, n, med(r, nr), no, bad
      exit bad > 0}' "$out/episodes.csv" | tee -a "$out/summary.txt" || true
  awk -F, 'NR > 1 {e[$2, ++c[$2]] = $3; if (!($2 in seen)) {seen[$2] = 1; order[++np] = $2}}
    function med5(p, from,   v, i, j, t, m) {m = 0; for (i = from; i < from + 5; i++) v[++m] = e[p, i]
      for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (v[j] < v[i]) {t = v[i]; v[i] = v[j]; v[j] = t}
      return v[3]}
    END {printf "  %-22s %s\n", "process", "max RSS [MiB], median of the first 5 -> last 5 episodes"
      for (k = 1; k <= np; k++) {p = order[k]; if (c[p] < 10) {printf "  %-22s %d episodes: too few to compare\n", p, c[p]; continue}
        a = med5(p, 1); b = med5(p, c[p] - 4); g = (b - a) / a * 100
        printf "  %-22s %6.0f -> %6.0f  %+6.1f%%\n", p, a, b, g; if (g > 15) {print "FAIL: " p " grew from episode to episode"; bad = 1}}
      exit bad}' "$out/episode_rss.csv" | tee -a "$out/summary.txt" || true
  say "/dev/shm data-sharing segments: $shm0 before the episodes, $(shm_segments) after"
fi

# ---- 2. one long-lived system, renderer killed and respawned ----
if [ "$long_s" -gt 0 ]; then
  mkdir -p "$out/long"
  log="$out/long/launch.log"
  shm0=$(shm_segments)
  start_pose='{position: {x: -1.5, y: 0.0, z: 8.35}, orientation: {x: 0.0, y: 0.0, z: 0.0, w: 1.0}}'
  unav launch launch_scripts/pipe_inspection_turbid.launch.yaml output_dir:="$out/long/run" duration:=0 \
    renderer_respawn:=true renderer_required:=false >"$log" 2>&1 &
  launch_pid=$!
  trap 'kill -INT $launch_pid 2>/dev/null || true; wait $launch_pid 2>/dev/null || true' EXIT
  sleep 10
  # name:pid of every process, the latest start of each name (a respawned renderer has a new pid).
  processes() {
    grep -o '\[[a-z_]*-[0-9]*\]: process started with pid \[[0-9]*\]' "$log" \
      | sed 's/\[\([a-z_]*\)-[0-9]*\]: process started with pid \[\([0-9]*\)\]/\1 \2/' \
      | awk '{p[$1] = $2} END {for (n in p) print n ":" p[n]}'
  }
  episodes_started() { grep -c "]: episode [0-9]*: the vehicle is at" "$log" || true; }
  [ -n "$(processes)" ] || { say "FAIL: no process started"; tail -20 "$log"; exit 1; }
  echo "t_s,process,pid,rss_kb,sim_time_s,open_fds" >"$out/long_rss.csv"
  sample() {
    local sim
    sim=$(timeout 10 unav topic echo /clock --once 2>/dev/null | awk '$1=="sec:"{s=$2} $1=="nanosec:"{printf "%.3f", s + $2 / 1e9; exit}')
    for n in $(processes); do
      local name=${n%%:*} pid=${n##*:} rss fds
      rss=$(awk '/VmRSS/{print $2}' "/proc/$pid/status" 2>/dev/null || echo dead)
      fds=$(ls "/proc/$pid/fd" 2>/dev/null | wc -l)
      echo "$SECONDS,$name,$pid,${rss:-dead},${sim:-none},$fds" >>"$out/long_rss.csv"
    done
  }
  end=$((SECONDS + long_s))
  next_episode=$((SECONDS + episode_s))
  next_kill=$((SECONDS + respawn_s))
  resets=0 resent=0 kills=0 respawned=0
  while [ $SECONDS -lt $end ]; do
    sample
    if [ $SECONDS -ge $next_episode ]; then
      # A one-shot publish of a volatile topic can be lost on a loaded machine (ros2 topic pub
      # --once has the same caveat): wait for the episode's log line, send again once if missing.
      started=$(episodes_started)
      for attempt in 1 2; do
        unav topic pub --once -w 1 /rov/sim/reset geometry_msgs/msg/Pose "$start_pose" >/dev/null 2>&1 || true
        for _ in $(seq 1 30); do
          [ "$(episodes_started)" -gt "$started" ] && break
          sleep 0.5
        done
        [ "$(episodes_started)" -gt "$started" ] && break
        resent=$((resent + 1))
      done
      resets=$((resets + 1))
      next_episode=$((next_episode + episode_s))
    fi
    if [ $SECONDS -ge $next_kill ]; then
      old=$(processes | awk -F: '$1=="underwater_renderer" {print $2}')
      kill -9 "$old" 2>/dev/null && kills=$((kills + 1))
      for _ in $(seq 1 60); do
        new=$(processes | awk -F: '$1=="underwater_renderer" {print $2}')
        [ "$new" != "$old" ] && kill -0 "$new" 2>/dev/null && { respawned=$((respawned + 1)); break; }
        sleep 0.5
      done
      next_kill=$((next_kill + respawn_s))
    fi
    sleep 30
  done
  sample
  kill -INT "$launch_pid" 2>/dev/null || true
  wait "$launch_pid" 2>/dev/null || true
  trap - EXIT
  sleep 1
  episodes=$(episodes_started)
  say "long-lived system: $((long_s / 60)) min, $(processes | wc -w) processes"
  say "  episodes: $((episodes + 1)) ($resets resets, $episodes started; $resent sent a second time after 15 s without a start)"
  [ "$episodes" -eq "$resets" ] || say "FAIL: $resets resets sent but $episodes episodes started"
  say "  renderer: $kills times killed (SIGKILL), $respawned respawned"
  [ "$kills" -eq "$respawned" ] || say "FAIL: the renderer was killed $kills times but respawned $respawned"
  say "  lockstep holds logged (a participant late by 3 s or more): $(grep -c "lockstep: holding at" "$log" || true)"
  ds="$out/long/run"
  frames=$(grep -vc '^#' "$ds/rgb.txt" 2>/dev/null || true)
  last=$(grep -v '^#' "$ds/rgb.txt" 2>/dev/null | tail -1 | cut -d' ' -f1)
  poses=$(awk -v t="${last:-0}" '!/^#/ && $1 <= t + 1e-9' "$ds/groundtruth.txt" 2>/dev/null | wc -l)
  gap=$(grep -v '^#' "$ds/rgb.txt" 2>/dev/null | awk 'NR == 1 {t0 = $1} {e = t0 + (NR - 1) * 0.1; if (($1 - e)^2 > 1e-10) {print "frame " NR " at " $1 " s, expected " e; exit}}')
  say "  frames: ${frames:-0} (to ${last:-?} s), poses up to the last frame: $poses"
  if [ -n "$gap" ] || [ "${frames:-0}" -eq 0 ] || [ "$frames" -ne "$poses" ]; then
    say "FAIL: frames lost or doubled (${gap:-frames $frames, poses $poses})"
  fi
  say "  /dev/shm data-sharing segments: $shm0 before, $(shm_segments) after the launch stopped ($(shm_mb) MB)"
  [ "$(shm_segments)" -le "$shm0" ] || say "FAIL: data-sharing segments left in /dev/shm"
  if grep -q ",dead," "$out/long_rss.csv"; then
    say "FAIL: a process died: $(grep ',dead,' "$out/long_rss.csv" | cut -d, -f2 | sort -u | tr '\n' ' ')"
  fi
  first_sim=$(awk -F, 'NR>1 && $5!="none"{print $5; exit}' "$out/long_rss.csv")
  last_sim=$(awk -F, 'NR>1 && $5!="none"{v=$5} END{print v}' "$out/long_rss.csv")
  say "  simulated time: ${first_sim:-?} s -> ${last_sim:-?} s"
  if [ -z "$first_sim" ] || ! awk -F, 'NR>1 && $2=="physics_server" {if ($5=="none" || (seen && $5<=prev)) bad=1; prev=$5; seen=1}
       END {exit bad}' "$out/long_rss.csv"; then
    say "FAIL: simulated time did not advance in every interval (a stuck lockstep barrier?)"
  fi
  # Per process (name and pid: each renderer life on its own): RSS and open files at its second
  # sample and at its last (allocations settle in the first 30 s).
  awk -F, 'NR>1 && $4!="dead" {k = $2 "[" $3 "]"; n[k]++; if (n[k]==2) {a[k]=$4; fa[k]=$6} b[k]=$4; fb[k]=$6; name[k]=$2}
       END {bad=0; printf "  %-30s %10s    %10s  %8s  %s\n", "process [pid]", "RSS [kB]", "", "growth", "open fds";
            for (k in b) { if (n[k] < 3) continue; g=(b[k]-a[k])/a[k]*100;
            printf "  %-30s %10d -> %10d  %+7.1f%%  %d -> %d\n", k, a[k], b[k], g, fa[k], fb[k];
            if ((g>5 && name[k]!="trajectory_evaluator") || fb[k]>fa[k]) {bad=1; print "FAIL: " k " grew"} }
            exit bad}' "$out/long_rss.csv" | tee -a "$out/summary.txt" || true
fi
if grep -q FAIL "$out/summary.txt"; then
  echo "soak: FAILED ($out/summary.txt)"
  exit 1
fi
echo "soak: ok ($out/summary.txt)"
