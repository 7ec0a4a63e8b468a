#!/usr/bin/env bash
# Configures a build folder with the options tools/demo.sh and tools/test.sh
# share, so that switching between the two rebuilds nothing: the demo builds
# its targets in build/, the tests then add only their own (the test
# executables and what they need).
#   tools/configure.sh             build/       RelWithDebInfo
#   tools/configure.sh --sanitize  build-asan/  RelWithDebInfo + ASan/UBSan
# Prints the folder. Warnings are errors in CI (CI=true); elsewhere a newer
# compiler's new warning must not stop a user's build.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=build sanitize=OFF
[ "${1:-}" = "--sanitize" ] && dir=build-asan sanitize=ON
werror=OFF
[ "${CI:-}" = true ] && werror=ON
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTRUECUT_SANITIZE=$sanitize \
      -DTRUECUT_WERROR=$werror -DTRUECUT_BUILD_TESTS=ON >/dev/null
echo "$dir"
