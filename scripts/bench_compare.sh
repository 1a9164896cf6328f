#!/usr/bin/env bash
# Benchmark history in one run (docs/testing.md, "Benchmark history"): builds the benchmarks of two
# commits side by side, runs them interleaved on this machine (ref, new, ref, new, ...) and prints
# each figure of both with the new/ref ratio of the medians and the spread (min-max) of the runs.
#
#   scripts/bench_compare.sh REF [NEW] [-n REPEATS] [-o OUT_DIR] [-w WORK_DIR] [-b REGEX]
#                            [--build-only] [--no-build]
#
# REF, NEW   commits (anything `git rev-parse` takes). Without NEW: the working tree as it is now
#            (tracked and untracked files that git does not ignore, uncommitted changes included).
# -n N       runs of each benchmark on each side (default 3): the spread shows the noise.
# -o DIR     where the table (bench_compare.md), the raw runs (runs.csv) and every run's output
#            (logs/) go (default: out/bench_compare in the repository).
# -w DIR     the two trees, WORK/ref and WORK/new, each src/ (a git worktree of the commit, or a
#            copy of the working tree), build/, install/, log/; kept between runs, so a second run
#            rebuilds only what changed (default: $UNAV_BENCH_WORK or ~/.cache/unav_bench_compare).
# -b REGEX   only the benchmarks whose key matches (keys: physics physics_server control renderer
#            sonar slam pipe_env latency bag ardupilot).
# --build-only builds both sides and stops; --no-build runs what the last build left in WORK.
# Environment: BENCH_NICE (default 19) is the nice level of every build and run, MAKEFLAGS (default
# -j2) the build's parallel jobs; colcon builds one package at a time. ccache, when installed, is
# shared by both trees (CCACHE_BASEDIR = WORK: identical files of the two commits hit the same entry).
#
# What it builds: the packages holding benchmarks (bench/) and their dependencies, with
# -DBUILD_TESTING=OFF -DUNAV_BUILD_BENCHMARKS=ON where the commit has that switch (src/unav_cmake),
# else -DBUILD_TESTING=OFF alone; a benchmark target still defined only with BUILD_TESTING=ON (the
# renderer's, in 592fdb8 and up to now) is then built alone in its package's build folder with
# BUILD_TESTING switched on for that configure and off again after it.
#
# What it reads: every benchmark prints `BENCH <id> <value> <unit>` lines (unav_common/bench.hpp);
# bench_physics is Google Benchmark, run with --benchmark_format=json (CPU time per step). Commits
# whose benchmarks predate those lines (592fdb8) are read from their human-readable output with one
# pattern per benchmark (legacy() below, giving the same ids); overlaying today's bench/ sources on
# such a commit does not compile (the renderer, SLAM and runtime APIs they use changed). A
# benchmark missing on one side (not there yet, failed to build or to run) shows as "-".
# GL benchmarks run headless on EGL (Mesa llvmpipe without a GPU) as the tests do, with the tree as
# a resource root (UNAV_RESOURCE_PATH).
set -euo pipefail

usage() { sed -n '5,23p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }

REPO=$(git -C "$(dirname "$0")/.." rev-parse --show-toplevel)
REPEATS=3
OUT="$REPO/out/bench_compare"
WORK="${UNAV_BENCH_WORK:-${XDG_CACHE_HOME:-$HOME/.cache}/unav_bench_compare}"
ONLY='.'
BUILD=1
RUN=1
POS=()
while [ $# -gt 0 ]; do
  case "$1" in
    -n) REPEATS="$2"; shift 2 ;;
    -o) OUT="$2"; shift 2 ;;
    -w) WORK="$2"; shift 2 ;;
    -b) ONLY="$2"; shift 2 ;;
    --build-only) RUN=0; shift ;;
    --no-build) BUILD=0; shift ;;
    -h|--help) usage ;;
    -*) echo "bench_compare: unknown option $1" >&2; usage ;;
    *) POS+=("$1"); shift ;;
  esac
done
[ ${#POS[@]} -ge 1 ] && [ ${#POS[@]} -le 2 ] || usage
NICE="${BENCH_NICE:-19}"
export MAKEFLAGS="${MAKEFLAGS:--j2}"
mkdir -p "$WORK" "$OUT"
WORK=$(cd "$WORK" && pwd)
OUT=$(cd "$OUT" && pwd)
# Nothing of another workspace may leak into the builds or the runs.
unset AMENT_PREFIX_PATH CMAKE_PREFIX_PATH COLCON_PREFIX_PATH UNAV_RESOURCE_PATH
export CCACHE_BASEDIR="$WORK" CCACHE_NOHASHDIR=1

# key package target: every benchmark of the workspace.
BENCHES=(
  "physics unav_physics bench_physics"
  "physics_server unav_physics bench_physics_server"
  "control unav_control bench_control"
  "renderer unav_renderer bench_unav_renderer"
  "sonar unav_renderer bench_unav_sonar"
  "slam unav_localization bench_mono_slam"
  "pipe_env unav_sim bench_pipe_env"
  "latency unav_runtime bench_latency"
  "bag unav_bag bench_unav_bag"
  "ardupilot unav_autopilot bench_ardupilot_json"
)

# The arguments of one benchmark's run on a side (SRC: that side's sources, SCRATCH: a temp dir).
bench_args() {
  local key=$1 src=$2 scratch=$3
  case "$key" in
    physics) echo "--benchmark_format=json" ;;
    physics_server) echo "$src/config/vehicles/bluerov2_heavy.yaml 3" ;;
    renderer)  # 40 frames; --quick (where the benchmark has it): the default options' row only
      if grep -q -- '"--quick"' "$src/packages/unav_renderer/bench/bench_renderer.cpp"; then
        echo "40 --quick"
      else
        echo "40"
      fi ;;
    sonar) echo "20" ;;
    latency) echo "1000 150" ;;
    bag) echo "$scratch/bag 5" ;;
    ardupilot) echo "20000" ;;
    *) echo "" ;;
  esac
}

REF_SHA=$(git -C "$REPO" rev-parse --verify "${POS[0]}^{commit}")
if [ ${#POS[@]} -eq 2 ]; then
  NEW_SHA=$(git -C "$REPO" rev-parse --verify "${POS[1]}^{commit}")
  NEW_DESC="$(git -C "$REPO" log -1 --format='%h %s' "$NEW_SHA" | cut -c1-90)"
else
  NEW_SHA=""
  NEW_HEAD=$(git -C "$REPO" rev-parse HEAD)
  dirty=$(git -C "$REPO" status --porcelain | wc -l)
  NEW_DESC="$(git -C "$REPO" log -1 --format='%h' HEAD) + working tree ($dirty paths changed or untracked)"
fi
REF_DESC="$(git -C "$REPO" log -1 --format='%h %s' "$REF_SHA" | cut -c1-90)"

# A side's sources: a detached worktree of the commit, or a copy of the working tree where only
# the files whose content differs from the last copy are written (with a new mtime, so make
# rebuilds what depends on them) and files gone from the working tree are removed.
prepare_tree() {
  local dir=$1 sha=$2
  if [ -n "$sha" ]; then
    if [ -f "$dir/.git" ] && git -C "$dir" rev-parse --git-dir >/dev/null 2>&1; then
      git -C "$dir" checkout -q --detach --force "$sha"
      git -C "$dir" clean -q -fd
    else
      rm -rf "$dir"
      git -C "$REPO" worktree prune
      git -C "$REPO" worktree add -q --detach "$dir" "$sha"
    fi
  else
    if [ -f "$dir/.git" ]; then git -C "$REPO" worktree remove --force "$dir"; fi
    mkdir -p "$dir"
    git -C "$REPO" ls-files -z -co --exclude-standard | python3 -c '
import filecmp, os, shutil, sys
src, dst = sys.argv[1], sys.argv[2]
want = {p for p in sys.stdin.buffer.read().decode().split("\0") if os.path.isfile(os.path.join(src, p))}
for p in want:
    s, d = os.path.join(src, p), os.path.join(dst, p)
    if not (os.path.isfile(d) and filecmp.cmp(s, d, shallow=False)):
        os.makedirs(os.path.dirname(d), exist_ok=True)
        shutil.copyfile(s, d)
        shutil.copymode(s, d)
for root, _, files in os.walk(dst):
    for f in files:
        if os.path.relpath(os.path.join(root, f), dst) not in want:
            os.remove(os.path.join(root, f))
' "$REPO" "$dir"
  fi
}

bench_packages() {
  local b
  for b in "${BENCHES[@]}"; do set -- $b; echo "$2"; done | sort -u
}

# Run a command niced in a side's environment: its install/setup.bash sourced (its packages on
# CMAKE_PREFIX_PATH and LD_LIBRARY_PATH, as colcon gives them), the side's tree a resource root.
in_side() {
  local T="$WORK/$1"
  shift
  (
    set +u
    if [ -f "$T/install/setup.bash" ]; then source "$T/install/setup.bash"; fi
    set -u
    export UNAV_RESOURCE_PATH="$T/src"
    exec nice -n "$NICE" "$@"
  )
}

# Build one side (ref or new) into WORK/side/{build,install}; its build.log says which packages
# colcon finished (only their benchmarks run).
build_side() {
  local side=$1 T="$WORK/$1" want=() p args pkgs b key pkg target bdir
  pkgs=$(colcon --log-base /dev/null list --base-paths "$T/src" -n)
  for p in $(bench_packages); do grep -qx "$p" <<<"$pkgs" && want+=("$p"); done
  args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DBUILD_TESTING=OFF)
  grep -rqs UNAV_BUILD_BENCHMARKS "$T/src/src/unav_cmake" && args+=(-DUNAV_BUILD_BENCHMARKS=ON)
  if command -v ccache >/dev/null; then
    args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  fi
  echo "[$side] building ${want[*]} and what they need (log: $T/build.log)"
  local t0=$SECONDS
  (cd "$T/src" && nice -n "$NICE" colcon --log-base "$T/log" build --base-paths "$T/src" \
    --build-base "$T/build" --install-base "$T/install" --executor parallel --parallel-workers 1 \
    --continue-on-error --packages-up-to "${want[@]}" --event-handlers console_cohesion- status- \
    --cmake-args "${args[@]}") >"$T/build.log" 2>&1 ||
    echo "[$side] the build had errors (see $T/build.log); the benchmarks that built still run" >&2
  # Benchmark targets defined only with BUILD_TESTING=ON: configured on, built alone, off again.
  local -A gated=()
  local targets
  for b in "${BENCHES[@]}"; do
    read -r key pkg target <<<"$b"
    bdir="$T/build/$pkg"
    grep -q "^Finished <<< $pkg " "$T/build.log" && [ -f "$bdir/CMakeCache.txt" ] || continue
    targets=$(cmake --build "$bdir" --target help 2>/dev/null || true)
    grep -qE "(^|[ .])$target(:| |$)" <<<"$targets" && continue
    grep -qs "add_executable($target " "$T/src/src/$pkg/CMakeLists.txt" "$T/src/packages/$pkg/CMakeLists.txt" ||
      continue
    gated[$pkg]+=" $target"
  done
  for pkg in "${!gated[@]}"; do
    bdir="$T/build/$pkg"
    echo "[$side] $pkg:${gated[$pkg]} need BUILD_TESTING=ON: building them alone"
    for target in ${gated[$pkg]}; do rm -f "$bdir/$target"; done
    { in_side "$side" cmake -DBUILD_TESTING=ON "$bdir" &&
      in_side "$side" cmake --build "$bdir" --target ${gated[$pkg]}; } >>"$T/build.log" 2>&1 ||
      echo "[$side] building${gated[$pkg]} failed (see $T/build.log)" >&2
    in_side "$side" cmake -DBUILD_TESTING=OFF "$bdir" >>"$T/build.log" 2>&1 || true
  done
  echo "[$side] build done in $((SECONDS - t0)) s"
}

# The executable of a benchmark on a side, or nothing.
bench_bin() {
  local T="$WORK/$1" pkg=$2 target=$3
  grep -q "^Finished <<< $pkg " "$T/build.log" 2>/dev/null || return 0
  for f in "$T/build/$pkg/$target" "$T/install/$pkg/lib/$pkg/$target"; do
    if [ -x "$f" ]; then echo "$f"; return 0; fi
  done
}

T_START=$(date '+%Y-%m-%d %H:%M:%S %Z')
S0=$SECONDS
if [ "$BUILD" = 1 ]; then
  prepare_tree "$WORK/ref/src" "$REF_SHA"
  prepare_tree "$WORK/new/src" "$NEW_SHA"
  build_side ref
  build_side new
fi
BUILD_S=$((SECONDS - S0))
[ "$RUN" = 1 ] || exit 0

rm -rf "$OUT/logs"
mkdir -p "$OUT/logs"
MANIFEST="$OUT/logs/manifest.tsv"
: >"$MANIFEST"
SCRATCH=$(mktemp -d)
trap 'rm -rf "$SCRATCH"' EXIT
R0=$SECONDS
LOAD0=$(cut -d' ' -f1-3 /proc/loadavg)
for rep in $(seq 1 "$REPEATS"); do
  for b in "${BENCHES[@]}"; do
    read -r key pkg target <<<"$b"
    [[ "$key" =~ $ONLY ]] || continue
    for side in ref new; do
      T="$WORK/$side"
      bin=$(bench_bin "$side" "$pkg" "$target")
      stem="$OUT/logs/${rep}_${side}_${key}"
      if [ -z "$bin" ]; then
        printf '%s\t%s\t%s\tmissing\t0\n' "$rep" "$side" "$key" >>"$MANIFEST"
        continue
      fi
      read -ra args <<<"$(bench_args "$key" "$T/src" "$SCRATCH")"
      echo "[run $rep/$REPEATS] $side $key"
      t0=$SECONDS
      rc=0
      (cd "$SCRATCH" && in_side "$side" timeout 900 "$bin" "${args[@]}") >"$stem.out" 2>"$stem.err" || rc=$?
      printf '%s\t%s\t%s\t%s\t%s\n' "$rep" "$side" "$key" "$rc" "$((SECONDS - t0))" >>"$MANIFEST"
    done
  done
done
RUN_S=$((SECONDS - R0))

CPU=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
export BC_OUT="$OUT" BC_REF="$REF_SHA" BC_NEW="${NEW_SHA:-$NEW_HEAD}" \
  BC_REF_DESC="$REF_DESC" BC_NEW_DESC="$NEW_DESC" BC_REPEATS="$REPEATS" BC_NPROC="$(nproc)" BC_CPU="$CPU" \
  BC_START="$T_START" BC_END="$(date '+%Y-%m-%d %H:%M:%S %Z')" BC_BUILD_S="$BUILD_S" BC_RUN_S="$RUN_S" \
  BC_NICE="$NICE" BC_LOAD="$LOAD0 at the start, $(cut -d' ' -f1-3 /proc/loadavg) at the end" \
  BC_KEYS="$(for b in "${BENCHES[@]}"; do echo "${b%% *}"; done)"
/usr/bin/env python3 - <<'PY'
import csv, json, math, os, re, statistics

E = os.environ
out = E["BC_OUT"]
logs = os.path.join(out, "logs")


def read(path):
    try:
        with open(path, errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def bench_lines(text):
    figs = []
    for m in re.finditer(r"^BENCH (\S+) (\S+) (\S+)\s*$", text, re.M):
        try:
            v = float(m[2])
        except ValueError:
            continue
        if math.isfinite(v):
            figs.append((m[1], v, m[3]))
    return figs


def gbench(text):
    """bench_physics (Google Benchmark, --benchmark_format=json): CPU time per iteration in ns."""
    try:
        data = json.loads(text)
    except ValueError:
        return []
    scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
    names = {"BM_DynamicsStep": "dynamics_step", "BM_SimulatorStep": "simulator_step"}
    figs = []
    for b in data.get("benchmarks", []):
        if b.get("run_type", "iteration") != "iteration" or "/" not in b["name"]:
            continue
        fam, var = b["name"].split("/", 1)
        var = {"velocity_verlet": "verlet"}.get(var, var)
        figs.append((f"physics/{names.get(fam, fam.lower())}_{var}_ns",
                     b["cpu_time"] * scale.get(b.get("time_unit", "ns"), 1.0), "ns"))
    return figs


def legacy(key, text):
    """Figures of a benchmark that predates the BENCH lines, from its human-readable output."""
    figs = []

    def add(i, v, u):
        figs.append((i, float(v), u))

    def each(pattern):
        return re.finditer(pattern, text, re.M)

    if key == "physics_server":
        for m in each(r"^\| (no subscribers|odometry subscriber in another participant) \| ([\d.]+) \|"):
            sub = "_odom_subscriber" if m[1].startswith("odometry") else ""
            add(f"physics/server_lockstep{sub}_x_real_time", m[2], "x_real_time")
    elif key == "control":
        for m in each(r"solve time\s+p50 ([\d.]+) ms\s+p90 [\d.]+ ms\s+p99 ([\d.]+) ms"):
            add("control/mpc_solve_p50_ms", m[1], "ms")
            add("control/mpc_solve_p99_ms", m[2], "ms")
        for m in each(r"^\s+iterations\s+p50 \S+\s+p99 \S+\s+max \S+\s+mean ([\d.]+)"):
            add("control/mpc_iterations_mean", m[1], "iterations")
        for m in each(r"thread CPU p50 ([\d.]+) / p99 ([\d.]+)"):
            add("control/mpc_replay_cpu_p50_ms", m[1], "ms")
            add("control/mpc_replay_cpu_p99_ms", m[2], "ms")
        for m in each(r"^Allocation \((\w+), \d+ thrusters\): ([\d.]+) ns"):
            add(f"control/allocate_{m[1]}_ns", m[2], "ns")
    elif key == "renderer":
        for m in each(r"^full \(default options\)\s+(\S+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)"):
            add(f"renderer/{m[1]}_median_ms", m[4], "ms")
            add(f"renderer/{m[1]}_sync_fps", m[2], "fps")
            add(f"renderer/{m[1]}_pipelined_fps", m[3], "fps")
        for m in each(r"^node pattern\s+([\d.]+)\s+([\d.]+)"):
            add("renderer/node_pattern_1_workers_ticks_per_s", m[1], "ticks_per_s")
            add("renderer/node_pattern_2_workers_ticks_per_s", m[2], "ticks_per_s")
    elif key == "sonar":
        for m in each(r"^((?:fls|sidescan)_\S+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+[\d.]+$"):
            add(f"sonar/{m[1]}_pings_per_s", m[2], "pings_per_s")
            add(f"sonar/{m[1]}_raster_ms", m[3], "ms")
            add(f"sonar/{m[1]}_accumulate_ms", m[4], "ms")
    elif key == "slam":
        parts = {"tracking (ORB + pose)": "orb_tracking", "tracking + mapping": "orb_tracking_mapping",
                 "mapping per keyframe": "orb_mapping_per_keyframe", "klt_vo monocular": "klt_vo_mono"}
        for m in each(r"^\s+(.+?)\s+mean\s+([\d.]+) ms\s+p50\s+([\d.]+)"):
            if m[1] in parts:
                add(f"slam/{parts[m[1]]}_mean_ms", m[2], "ms")
                add(f"slam/{parts[m[1]]}_p50_ms", m[3], "ms")
    elif key == "latency":
        cases = {"100 B Image": "latency_small", "640x480 rgb8 (921,600 B)": "latency_image",
                 "640x480 rgb8, throughput": "throughput_image"}
        paths = {"raw Fast DDS": "raw", "raw Fast DDS, data-sharing": "raw_data_sharing",
                 "unav runtime": "runtime", "unav runtime, data-sharing": "runtime_data_sharing",
                 "unav runtime, secured": "runtime_secured"}
        for m in each(r"^\| (.+?) \| (.+?) \| (\d+) \| [\d.]+ Hz \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \|$"):
            if m[1] not in cases or m[2] not in paths or int(m[3]) == 0:
                continue
            i = f"runtime/{cases[m[1]]}_{paths[m[2]]}"
            if cases[m[1]].startswith("throughput"):
                add(f"{i}_mb_per_s", m[6], "MB_per_s")
            else:
                add(f"{i}_p50_ms", m[4], "ms")
                add(f"{i}_p99_ms", m[5], "ms")
    elif key == "pipe_env":
        for m in each(r"^reset \(.*?\): median ([\d.]+) ms"):
            add("sim/pipe_env_reset_ms", m[1], "ms")
        vec = {}
        for m in each(r"^(\w+)\s+(\d+)x(\d+)\s+envs=(\d+) contexts=\d+:\s+([\d.]+) steps/s\s+\(([\d.]+) ms/step: "
                      r"physics ([\d.]+), mpc\+alloc ([\d.]+), render ([\d.]+), readback ([\d.]+)"):
            i = f"sim/pipe_env_{m[1]}_{m[2]}x{m[3]}"
            if m[4] == "1":
                add(f"{i}_steps_per_s", m[5], "steps_per_s")
                for part, v in zip(("physics", "control", "render", "readback"), m.groups()[6:10]):
                    add(f"{i}_{part}_ms", v, "ms")
            else:  # the vector runs alternate one context, then as many as it chooses
                vec.setdefault(f"{i}_{m[4]}envs", []).append(float(m[5]))
        for i, v in vec.items():
            for name, runs in (("1ctx", v[0::2]), ("auto_ctx", v[1::2])):
                if runs:
                    add(f"{i}_{name}_steps_per_s", sum(runs) / len(runs), "steps_per_s")
    elif key == "bag":
        for m in each(r"^(\w+)/(\w+)\s+\d+\s+[\d.]+\s+[\d.]+\s+([\d.]+)"):
            add(f"bag/write_{m[1]}_{m[2]}_mb_per_s", m[3], "MB_per_s")
    elif key == "ardupilot":
        for m in each(r"^bench ardupilot_json\.(\w+) ([\d.]+) (\S+)"):
            add(f"autopilot/ardupilot_json_{m[1]}_{m[3]}", m[2], m[3])
    return figs


def figures(key, text):
    if key == "physics":
        return gbench(text)
    return bench_lines(text) or legacy(key, text)


runs = []  # (rep, side, key, id, value, unit)
failures = []
with open(os.path.join(logs, "manifest.tsv")) as f:
    for line in f:
        rep, side, key, rc, secs = line.rstrip("\n").split("\t")
        if rc == "missing":
            continue
        stem = os.path.join(logs, f"{rep}_{side}_{key}")
        figs = figures(key, read(stem + ".out"))
        if rc != "0" or not figs:
            failures.append(f"{side} {key} run {rep}: exit {rc}, {len(figs)} figures after {secs} s "
                            f"(logs/{rep}_{side}_{key}.out/.err)")
        for i, v, u in figs:
            runs.append((int(rep), side, key, i, v, u))

# Rows by benchmark, each in the new side's order, then the figures only the ref side has.
keys = E["BC_KEYS"].split()
pos = {}
for n, (rep, side, key, i, v, u) in enumerate(runs):
    pos.setdefault((i, side), (keys.index(key), n))
order = sorted({r[3] for r in runs},
               key=lambda i: pos[i, "new"] if (i, "new") in pos else (pos[i, "ref"][0], 10**9 + pos[i, "ref"][1]))

gl = ""
for name in sorted(os.listdir(logs)):
    m = re.search(r"^unav_renderer bench: (.+?) via |^sonar benchmark: .*?, (.+?) \(EGL",
                  read(os.path.join(logs, name)), re.M)
    if m:
        gl = m[1] or m[2]
        break

stats = {}
for i in order:
    for side in ("ref", "new"):
        v = [r[4] for r in runs if r[3] == i and r[1] == side]
        u = next(r[5] for r in runs if r[3] == i)
        stats[i, side] = (statistics.median(v), min(v), max(v), len(v)) if v else None
        stats[i, "unit"] = u


def fmt(v):
    a = abs(v)
    if a >= 1000:
        return f"{v:.0f}"
    if a >= 100:
        return f"{v:.1f}"
    if a >= 1:
        return f"{v:.2f}"
    return f"{v:.3g}"


def direction(unit):  # -1: lower is better, +1: higher is better, 0: neither
    if unit in ("ns", "us", "ms", "s"):
        return -1
    if unit in ("fps", "x_real_time") or unit.endswith("_per_s"):
        return 1
    return 0


rows = []
for i in order:
    u = stats[i, "unit"]
    r, n = stats[i, "ref"], stats[i, "new"]
    ratio, change = "-", ""
    if r and n:
        ratio = f"{n[0] / r[0]:.3f}" if r[0] else "-"
        if min(r[3], n[3]) < 2:
            change = "(one run)"
        elif max(n[1] - r[2], r[1] - n[2]) > 0.005 * abs(r[0]):
            # the ranges do not overlap, by more than the 0.5 % that printed digits may lose
            d = direction(u) * (1 if n[0] > r[0] else -1)
            change = "better" if d > 0 else "worse" if d < 0 else "differs"
        else:
            change = "~ (within noise)"
    rows.append([i, u, fmt(r[0]) if r else "-", fmt(n[0]) if n else "-", ratio,
                 f"{fmt(r[1])}-{fmt(r[2])}" if r else "-", f"{fmt(n[1])}-{fmt(n[2])}" if n else "-", change])

head = ["id", "unit", "ref median", "new median", "new/ref", "ref min-max", "new min-max", "change"]
lines = [
    "# Benchmark history",
    "",
    f"- ref: {E['BC_REF']} ({E['BC_REF_DESC']})",
    f"- new: {E['BC_NEW']} ({E['BC_NEW_DESC']})",
    f"- machine: nproc {E['BC_NPROC']}, CPU {E['BC_CPU']}, GL {gl or 'n/a (no GL benchmark ran)'}; "
    f"load average {E['BC_LOAD']}; runs at nice {E['BC_NICE']}",
    f"- {E['BC_REPEATS']} runs a side, interleaved (ref, new, ref, new ...), {E['BC_START']} to {E['BC_END']}; "
    f"build {E['BC_BUILD_S']} s, runs {E['BC_RUN_S']} s",
    "- change: the two ranges (min-max) do not overlap (better / worse for the unit's direction), "
    "or they overlap (~ within noise)",
    "",
    "| " + " | ".join(head) + " |",
    "|" + "---|" * len(head),
]
lines += ["| " + " | ".join(r) + " |" for r in rows]
if failures:
    lines += ["", "Runs that failed or gave no figure:"] + [f"- {x}" for x in failures]
missing = sorted({l.split("\t")[1] + " " + l.split("\t")[2] for l in open(os.path.join(logs, "manifest.tsv"))
                  if l.split("\t")[3] == "missing"})
if missing:
    lines += ["", "Not built on that side (not in that commit, or its build failed): " + ", ".join(missing)]
text = "\n".join(lines) + "\n"
with open(os.path.join(out, "bench_compare.md"), "w") as f:
    f.write(text)
with open(os.path.join(out, "runs.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["repeat", "side", "commit", "benchmark", "id", "value", "unit"])
    for rep, side, key, i, v, u in runs:
        w.writerow([rep, side, E["BC_REF"] if side == "ref" else E["BC_NEW"], key, i, v, u])
print(text)
print(f"written: {out}/bench_compare.md, {out}/runs.csv, {out}/logs/")
PY
