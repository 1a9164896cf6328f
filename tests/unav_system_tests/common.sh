# Sourced first by every system test (`source "$(dirname "$0")/common.sh"`, the test's $1 is the
# workspace): strict mode; on an unexpected exit, the failing line and the tail of "$log" when the
# test set one; the workspace's environment; a DDS domain no other test on this machine holds
# (test_domain.sh); `py`, the Python of the workspace's venv.
set -euo pipefail
ws="${1:?usage: $0 WORKSPACE}"
unav_on_unexpected_exit() {
  echo "FAIL: unexpected exit at line $1: $2"
  if [ -n "${log:-}" ] && [ -f "$log" ]; then grep -v "Publishing\|I heard" "$log" | tail -30; fi
}
trap 'unav_on_unexpected_exit $LINENO "$BASH_COMMAND"' ERR
set +u; source "$ws/install/setup.bash"; set -u
source "$(dirname "${BASH_SOURCE[0]}")/test_domain.sh"
py="${UNAV_VENV:-$ws/.venv}/bin/python"

# shipped_spec OUT [SED_EXPRESSION...]: the shipped datagen spec (config/datagen/pipe_survey.yaml)
# with its files resolved in this workspace and the expressions applied, written to OUT.
shipped_spec() {
  local out=$1 e
  shift
  local args=(-e "s|^base_world: .*|base_world: $ws/worlds/pipe_inspection/world.yaml|"
              -e "s|^cameras_config: .*|cameras_config: $ws/config/sensors/bluerov2_cameras.yaml|")
  for e in "$@"; do args+=(-e "$e"); done
  sed "${args[@]}" "$ws/config/datagen/pipe_survey.yaml" >"$out"
}

# start_foxglove_bridge LOG: `unav foxglove` in the background on a random port, its output in LOG;
# sets bridge_pid, url (ws://127.0.0.1:PORT) and client (Foxglove's own libraries:
# src/unav_bag/test/foxglove/foxglove_client.mjs). Returns 1 (with the reason) when it did not start.
start_foxglove_bridge() {
  client="$ws/src/unav_bag/test/foxglove/foxglove_client.mjs"
  if [ ! -d "$ws/src/unav_bag/test/foxglove/node_modules/@foxglove/ws-protocol" ]; then
    echo "no node_modules/@foxglove/ws-protocol (scripts/install_deps.sh runs npm ci)"
    return 1
  fi
  local port=$((20000 + RANDOM % 20000))
  unav foxglove --port "$port" >"$1" 2>&1 &
  bridge_pid=$!
  url="ws://127.0.0.1:$port"
  for _ in $(seq 1 100); do
    grep -q "Foxglove WebSocket server on $url" "$1" && return 0
    sleep 0.1
  done
  echo "the bridge did not start: $(tail -3 "$1")"
  return 1
}
