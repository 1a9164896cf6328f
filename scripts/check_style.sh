#!/usr/bin/env bash
# Style gate for changed C++ files (STYLE.md item 11): clang-format (.clang-format) and clang-tidy
# (.clang-tidy, warnings as errors) on every .cpp/.hpp/.h file changed since BASE (default: the
# commit in .ci/style_base, where enforcement started). Needs a built workspace for clang-tidy
# (compile_commands.json per package); files outside any package's compile database are only
# format-checked. Usage: scripts/check_style.sh [BASE] [--fix]
set -euo pipefail
cd "$(dirname "$0")/.."
base="$(cat .ci/style_base)"
fix=0
for a in "$@"; do
  case "$a" in
    --fix) fix=1 ;;
    *) base="$a" ;;
  esac
done
command -v clang-format >/dev/null || { echo "check_style: clang-format missing (apt-get install clang-format)"; exit 1; }
if ! git cat-file -e "$base^{commit}" 2>/dev/null; then
  # A shallow clone lacks the base: check what the last commit changed instead.
  if git cat-file -e "HEAD~1^{commit}" 2>/dev/null; then
    echo "check_style: base $base not in this clone; checking the files of the last commit"
    base="HEAD~1"
  else
    echo "check_style: base $base not in this clone and no parent commit: nothing to compare; skipped"
    exit 0
  fi
fi
mapfile -t files < <(git diff --name-only --diff-filter=ACMR "$base" -- '*.cpp' '*.hpp' '*.h' | grep -v '^build/\|^install/' || true)
if [ ${#files[@]} -eq 0 ]; then echo "check_style: no C++ file changed since $base"; exit 0; fi
bad=0
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  if [ "$fix" -eq 1 ]; then clang-format -i "$f"; continue; fi
  clang-format --dry-run --Werror "$f" 2>/dev/null || { echo "check_style: $f is not clang-formatted (run scripts/check_style.sh --fix)"; bad=1; }
done
# clang-tidy on the changed .cpp files that a package's compile database knows, one process per
# core (each file's report printed whole), since the range of files grows with every round.
tidy_one() {
  local f="$1" db="build/$(basename "$(echo "$1" | cut -d/ -f1-2)")"
  [ -f "$db/compile_commands.json" ] && grep -q "\"file\": \"$PWD/$f\"" "$db/compile_commands.json" || return 0
  local out
  out=$(clang-tidy --quiet -p "$db" "$f" 2>/dev/null || true)
  if echo "$out" | grep -qE "(warning|error):"; then echo "$out" | grep -A3 -E "(warning|error):"; return 1; fi
}
if command -v clang-tidy >/dev/null && [ "${UNAV_SKIP_TIDY:-0}" != "1" ]; then
  export -f tidy_one
  cpps=()
  for f in "${files[@]}"; do case "$f" in *.cpp) [ -f "$f" ] && cpps+=("$f") ;; esac; done
  if [ ${#cpps[@]} -gt 0 ]; then
    printf '%s\n' "${cpps[@]}" | xargs -r -P "${UNAV_TIDY_JOBS:-$(nproc)}" -I{} bash -c 'tidy_one "$1"' _ {} || bad=1
  fi
fi
[ "$bad" -eq 0 ] && echo "check_style: ${#files[@]} changed file(s) since $base are clean"
exit "$bad"
