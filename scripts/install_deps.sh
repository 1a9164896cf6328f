#!/usr/bin/env bash
# Installs the Debian packages UNav-Sim needs, only those missing. Idempotent; needs root or sudo.
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build ccache git
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  colcon python3-colcon-cmake python3-colcon-core python3-colcon-test-result
  python3-colcon-package-selection python3-colcon-parallel-executor python3-colcon-output
  python3-colcon-defaults python3-colcon-metadata python3-colcon-recursive-crawl
  python3-colcon-library-path python3-colcon-bash python3-colcon-package-information
  libeigen3-dev libopencv-dev libceres-dev libassimp-dev
  libegl-dev libgles-dev libgl-dev libegl-mesa0 libgbm-dev libepoxy-dev
  libyaml-cpp-dev libcli11-dev libspdlog-dev nlohmann-json3-dev libwebsocketpp-dev libasio-dev
  libgtest-dev libgmock-dev libbenchmark-dev libsqlite3-dev libssl-dev libzstd-dev zlib1g-dev
  clang-format clang-tidy clang-14 libclang-rt-14-dev
  munge slurmctld slurmd slurm-client
  pybind11-dev python3-dev python3-venv python3-pytest python3-numpy python3-torch
  python3-pandas python3-matplotlib python3-tqdm python3-rich python3-typing-extensions
  python3-scipy python3-pil
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PKGS[@]} Debian packages present"
else
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "install_deps: installing ${#missing[@]} missing packages: ${missing[*]}"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q -o DPkg::Lock::Timeout=900 "${missing[@]}"
fi

# The learning stack: a venv made from Debian's Python with its site packages, so Debian's torch
# (1.13, CPU) is used. Debian's torch reports version 1.13.0a0, which pip does not count as
# >= 1.13: installing stable-baselines3 with its dependencies would pull a CUDA torch of several
# GB from PyPI. So the PyPI packages are installed pinned and without dependencies; everything
# else they import comes from the Debian packages above.
VENV="${UNAV_VENV:-$(cd "$(dirname "$0")/.." && pwd)/.venv}"
# The bag readers nobody here wrote, used by the tests to read our bags back: rosbags (both
# storages), mcap + mcap-ros2-support (MCAP, as Foxglove decodes it), with their dependencies
# pinned the same way (Debian's typing_extensions 4.4 is older than rosbags needs).
PY_PINS=(gymnasium==1.0.0 stable-baselines3==2.4.1 farama-notifications==0.0.4 cloudpickle==3.1.1
  rosbags==0.11.9 apsw==3.54.1.0 backports.zstd==1.8.0 ruamel.yaml==0.19.1 typing_extensions==4.16.0
  mcap==1.6.0 mcap-ros2-support==0.6.0 zstandard==0.25.0)
if [ ! -x "$VENV/bin/python" ]; then
  echo "install_deps: creating the Python venv $VENV (from /usr/bin/python3, with system site packages)"
  /usr/bin/python3 -m venv --system-site-packages "$VENV"
fi
if ! "$VENV/bin/python" - "${PY_PINS[@]}" <<'PYEOF'
import sys
from importlib.metadata import version, PackageNotFoundError
for pin in sys.argv[1:]:
    name, want = pin.split("==")
    try:
        if version(name) != want:
            sys.exit(1)
    except PackageNotFoundError:
        sys.exit(1)
PYEOF
then
  echo "install_deps: pip install --no-deps ${PY_PINS[*]}"
  "$VENV/bin/pip" install -q --no-deps "${PY_PINS[@]}"
fi
"$VENV/bin/python" -c "import gymnasium, stable_baselines3, torch, pandas, tqdm, rich, rosbags.rosbag2, mcap_ros2" \
  || { echo "install_deps: the venv $VENV cannot import the learning stack"; exit 1; }
echo "install_deps: Python venv $VENV ready (gymnasium, stable-baselines3 over Debian's torch)"

# The TypeScript readers Foxglove uses (test_foxglove_readers): Node.js from Debian when none is
# installed, then the pinned packages of src/unav_bag/test/foxglove/package-lock.json.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "install_deps: installing nodejs and npm (Debian)"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q -o DPkg::Lock::Timeout=900 nodejs npm
fi
FOXGLOVE_DIR="$(cd "$(dirname "$0")/.." && pwd)/src/unav_bag/test/foxglove"
if [ ! -f "$FOXGLOVE_DIR/node_modules/.package-lock.json" ] ||
   ! cmp -s "$FOXGLOVE_DIR/package-lock.json" "$FOXGLOVE_DIR/node_modules/.lock-installed"; then
  echo "install_deps: npm ci (Foxglove's readers, pinned) in $FOXGLOVE_DIR"
  (cd "$FOXGLOVE_DIR" && npm ci --no-audit --no-fund --loglevel=error && cp package-lock.json node_modules/.lock-installed)
fi
echo "install_deps: Foxglove's TypeScript readers ready ($(node --version))"
