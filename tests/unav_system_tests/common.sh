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
