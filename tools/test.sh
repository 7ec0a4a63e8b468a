#!/usr/bin/env bash
# The README's second command: install what is missing, build, run every test.
#   tools/test.sh              normal build in build/
#   tools/test.sh --sanitize   AddressSanitizer + UBSan build in build-asan/
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
dir=build type=RelWithDebInfo sanitize=OFF
if [ "${1:-}" = "--sanitize" ]; then
  dir=build-asan type=RelWithDebInfo sanitize=ON
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
fi
# Warnings are errors in CI (CI=true); elsewhere a newer compiler's new
# warning must not stop a user's build.
werror=OFF
[ "${CI:-}" = true ] && werror=ON
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=$type -DTRUECUT_SANITIZE=$sanitize -DTRUECUT_WERROR=$werror \
      -DTRUECUT_BUILD_TESTS=ON >/dev/null
cmake --build "$dir" -j"$(nproc)"
ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" --timeout 600
