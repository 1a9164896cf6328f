#!/bin/bash
# Packs the renderer's binaries and the shared libraries they need into DIR (default .devbundle,
# git-ignored through .git/info/exclude) so that they run on a bare GPU machine (another Linux,
# glibc >= Debian 12's, no Debian packages): bin.tar.xz, libs.tar.xz and run.sh. OpenCV's
# imgcodecs links GDAL and GDCM (~150 MB with their own needs) that the renderer never calls: they
# are replaced by stubs with the same names and the symbols imgcodecs imports (returning 0),
# which keeps the bundle at ~22 MB. The GL libraries (libglvnd) come from the machine or from
# Debian's .deb files unpacked there (libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2).
#   bash scripts/build.sh && bash scripts/gpu_bundle.sh [DIR]
# There: bash DIR/run.sh OUT   (bench, images, the renderer's tests; logs and PNGs under OUT)
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-.devbundle}
BINS=(build/unav_renderer/bench_unav_renderer install/unav_renderer/bin/unav_render_world
      build/unav_renderer/test_unav_renderer_render build/unav_renderer/test_unav_renderer_terrain_lod
      build/unav_renderer/test_unav_renderer_pool)
for b in "${BINS[@]}"; do [ -x "$b" ] || { echo "gpu_bundle: $b missing: run scripts/build.sh first" >&2; exit 1; }; done
export LC_ALL=C
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/stub" "$work/lib_dev" "$work/bin" "$DIR"
# The machine's own: the C library, the GL dispatch (libglvnd) and the C++ runtime (newer there).
skip='libc\.so|libm\.so|libdl\.so|libpthread|librt\.so|ld-linux|libGLX|libGLdispatch|libEGL|libGL\.so|libOpenGL|libresolv|libstdc\+\+|libgcc_s'
imgcodecs=$(ldd build/unav_renderer/bench_unav_renderer | awk '$1 ~ /libopencv_imgcodecs/ {print $3}')
stub() {  # stub REAL_LIB: its SONAME, exporting what imgcodecs imports from it
  local real=$1 soname
  soname=$(readelf -d "$real" | sed -n 's/.*SONAME.*\[\(.*\)\]/\1/p')
  nm -D --undefined-only "$imgcodecs" | awk '{print $2}' | sed 's/@.*//' | sort -u >"$work/want"
  nm -D -S --defined-only "$real" | awk 'NF==4 {print $4, $3, $2} NF==3 {print $3, $2, "8"}' | sort -u -k1,1 >"$work/have"
  join "$work/want" "$work/have" | while read -r name type size; do
    case $type in
      T | W | i) echo "long $name(void) { return 0; }" ;;
      *) echo "char $name[0x$size] __attribute__((aligned(16)));" ;;
    esac
  done >"$work/stub/$soname.c"
  gcc -shared -fPIC -o "$work/stub/$soname" -Wl,-soname,"$soname" "$work/stub/$soname.c"
}
for name in libgdal.so libgdcmMSFF.so libgdcmDSED.so; do
  real=$(ldd "$imgcodecs" | awk -v n="$name" 'index($1, n) == 1 {print $3}')
  [ -n "$real" ] && stub "$real"
done
set +u
# shellcheck disable=SC1091
source install/setup.bash
set -u
for b in "${BINS[@]}"; do
  LD_LIBRARY_PATH="$work/stub:${LD_LIBRARY_PATH:-}" ldd "$b" | awk '$3 ~ /^\// {print $3}'
  cp "$b" "$work/bin/"
done | sort -u | grep -v -E "$skip" | while read -r lib; do cp -L "$lib" "$work/lib_dev/$(basename "$lib")"; done
tar cf - -C "$work" lib_dev | xz -T2 -6 >"$DIR/libs.tar.xz"
tar cf - -C "$work" bin | xz -T2 -3 >"$DIR/bin.tar.xz"
cat >"$DIR/run.sh" <<'RUN'
#!/bin/bash
# On the GPU machine, from the repository's root: bash DIR/run.sh OUT
OUT=${1:?OUT folder}; D=$(dirname "$0"); mkdir -p "$OUT/img"
exec > >(tee "$OUT/log.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv 2>/dev/null
mkdir -p /tmp/unav_gpu && tar xJf "$D/libs.tar.xz" -C /tmp/unav_gpu && tar xJf "$D/bin.tar.xz" -C /tmp/unav_gpu
export LD_LIBRARY_PATH=/tmp/unav_gpu/lib_dev UNAV_RESOURCE_PATH=$PWD
B=/tmp/unav_gpu/bin
ldd $B/bench_unav_renderer | grep "not found"
for p in "0 0.3 8 3" "6 1.2 8.5 40"; do
  timeout 60 $B/unav_render_world worlds/pipe_inspection/world.yaml config/sensors/bluerov2_cameras.yaml \
    "$OUT/img/p${p%% *}" --pose $p --no-noise --no-snow
done
timeout 240 $B/bench_unav_renderer 300
# The tests name files under the checkout they were built in (UNAV_REPO_ROOT): link it if absent.
R=@REPO_ROOT@
[ -e "$R" ] || { mkdir -p "$(dirname "$R")" && ln -s "$PWD" "$R"; }
for t in test_unav_renderer_render test_unav_renderer_terrain_lod test_unav_renderer_pool; do
  timeout 120 $B/$t 2>&1 | grep -E "PASSED|FAILED|Failure"
done
RUN
sed -i "s|@REPO_ROOT@|$PWD|" "$DIR/run.sh"
chmod +x "$DIR/run.sh"
du -sh "$DIR"/*.tar.xz
