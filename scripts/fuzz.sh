#!/usr/bin/env bash
# Longer fuzzing than the test command's smoke runs: every libFuzzer target of tests/unav_fuzz for
# SECONDS each (default 300) from its corpus, new inputs kept in out/fuzz/<target>/. A crash
# leaves crash-* in out/fuzz/; copy it into tests/unav_fuzz/corpus/<target>/ as a regression
# input once fixed (the smoke run replays the corpus).
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]   (after scripts/build.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-300}"; shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_cdr fuzz_idl fuzz_mcap fuzz_trajectory fuzz_spec fuzz_launch fuzz_configs fuzz_params)
mkdir -p out/fuzz
for t in "${targets[@]}"; do
  exe=install/unav_fuzz/lib/unav_fuzz/$t
  [ -x "$exe" ] || { echo "fuzz.sh: $exe missing (scripts/build.sh builds it)"; exit 1; }
  mkdir -p "out/fuzz/$t"
  echo "== $t for $secs s"
  (cd out/fuzz && "../../$exe" -max_total_time="$secs" -max_len=4096 -rss_limit_mb=2048 -timeout=20 -print_final_stats=1 \
    "$t" "../../tests/unav_fuzz/corpus/$t" 2>&1 | grep -E "^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss|==[0-9]+==ERROR|SUMMARY)" || true)
done
ls out/fuzz/crash-* 2>/dev/null && { echo "fuzz.sh: crashes found (out/fuzz/crash-*)"; exit 1; }
echo "fuzz.sh: no crash"
