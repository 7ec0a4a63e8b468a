#!/usr/bin/env bash
# The README's second command: install what is missing, build, run every test.
#   tools/test.sh              normal build in build/ (the folder and options
#                              of tools/demo.sh: after the demo only the tests'
#                              own targets are built)
#   tools/test.sh --sanitize   AddressSanitizer + UBSan build in build-asan/
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
if [ "${1:-}" = "--sanitize" ]; then
  # intercept_tls_get_addr=0: LLVM's sanitizer runtime up to 16 (Debian 12
  # has clang 14) can take a dynamic TLS block that malloc placed at a
  # certain offset in its page for a glibc-2.19 header and read garbage as
  # its bounds; LeakSanitizer's tracer then crashes at exit after a passing
  # test ("Tracer caught signal 11"). The cutting component's TLS, dlopened
  # by the HAL, met it (CuttingComponent.FaceMills..., 2026-12-02). The
  # static TLS of threads is still scanned.
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:intercept_tls_get_addr=0
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
fi
dir=$(tools/configure.sh "$@")
# The tests and what they run (truecut_tests); in CI's normal half the whole
# tree, so the benchmarks keep compiling too.
target=truecut_tests
[ "${CI:-}" = true ] && [ "${1:-}" != "--sanitize" ] && target=all
cmake --build "$dir" -j"$(nproc)" --target $target
# The suite, then (normal build only) the comparisons with LinuxCNC itself,
# which run LinuxCNC in real time (about 15 s on 2 cores on their own,
# docs/linuxcnc.md), and the diagnosis cases on recordings from the
# independent planted generator (about 50 s on 2 cores, docs/diagnosis.md,
# "Independent planted recordings").
ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" --timeout 600 -LE "planted|linuxcnc"
if [ "${1:-}" != "--sanitize" ]; then
  ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" --timeout 600 -L linuxcnc
  ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" --timeout 900 -L planted
fi
