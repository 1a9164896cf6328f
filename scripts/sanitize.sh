#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (gcc): a separate build
# (build_asan/, install_asan/, log_asan/) of PACKAGES and what they depend on, then their tests.
# Any sanitizer report fails the test that triggered it (halt_on_error, exit code 1).
#   scripts/sanitize.sh                       # every package (long: a full second build)
#   scripts/sanitize.sh unav_runtime unav_bag # these packages and their dependencies
# Leak checking is off: Fast DDS and Mesa keep process-lifetime allocations that LSan reports.
set -euo pipefail
cd "$(dirname "$0")/.."
export MAKEFLAGS="${MAKEFLAGS:--j$(nproc)}"
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
select=()
[ $# -gt 0 ] && select=(--packages-up-to "$@")
colcon --log-base log_asan build --build-base build_asan --install-base install_asan \
  --event-handlers console_cohesion- status- "${select[@]}" \
  --cmake-args -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS=$flags" "-DCMAKE_C_FLAGS=$flags" \
  "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" "-DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=address,undefined"
# new_delete_type_mismatch=0: Fast DDS 2.9 frees its StatisticsReaderImpl with a sized delete of
# another type inside delete_datareader() (all frames in libfastrtps): its bug, not ours.
# alloc_dealloc_mismatch=0: with gcc 12, every std::stable_sort that takes a temporary buffer
# reports "operator new vs free": libstdc++'s get_temporary_buffer allocates with
# operator new(nothrow) and its __return_temporary_buffer's sized operator delete reaches ASan as
# free() (seen in AcousticModem::step, stl_tempbuf.h:74): the toolchain's, not ours.
export ASAN_OPTIONS="detect_leaks=0:new_delete_type_mismatch=0:alloc_dealloc_mismatch=0:halt_on_error=1:abort_on_error=0:exitcode=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
test_select=()
[ $# -gt 0 ] && test_select=(--packages-select "$@")
rc=0
colcon --log-base log_asan test --build-base build_asan --install-base install_asan --executor sequential \
  --event-handlers console_cohesion- status- --return-code-on-test-failure "${test_select[@]}" || rc=$?
colcon --log-base log_asan test-result --test-result-base build_asan --verbose | tail -40
grep -rl "ERROR: AddressSanitizer\|runtime error:" build_asan/*/Testing build_asan/*/test_results 2>/dev/null | head || true
exit "$rc"
