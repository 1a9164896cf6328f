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
  libyaml-cpp-dev libcli11-dev libspdlog-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev libsqlite3-dev
  clang-format clang-tidy
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PKGS[@]} Debian packages present"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install_deps: installing ${#missing[@]} missing packages: ${missing[*]}"
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q -o DPkg::Lock::Timeout=900 "${missing[@]}"
