#!/usr/bin/env bash
# Configures a build folder with the options tools/demo.sh and tools/test.sh
# share, so that switching between the two rebuilds nothing: the demo builds
# its targets in build/, the tests then add only their own (the test
# executables and what they need).
#   tools/configure.sh             build/       RelWithDebInfo
#   tools/configure.sh --sanitize  build-asan/  RelWithDebInfo + ASan/UBSan, clang if installed
# Prints the folder. Warnings are errors in CI (CI=true); elsewhere a newer
# compiler's new warning must not stop a user's build.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=build sanitize=OFF compilers=()
if [ "${1:-}" = "--sanitize" ]; then
  dir=build-asan sanitize=ON
  # clang (installed by install-deps.sh for fuzzing) builds the sanitized
  # tree in well under half of GCC's time (docs/reliability.md, "Sanitizers").
  command -v clang++ >/dev/null && compilers=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++)
fi
werror=OFF
[ "${CI:-}" = true ] && werror=ON
cmake -S . -B "$dir" "${compilers[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTRUECUT_SANITIZE=$sanitize \
      -DTRUECUT_WERROR=$werror -DTRUECUT_BUILD_TESTS=ON >/dev/null
echo "$dir"
