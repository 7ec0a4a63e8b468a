#!/usr/bin/env bash
# The README's first command: install what is missing, build, run the main job.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
# Same folder and flags as tools/test.sh, so switching between the two rebuilds nothing.
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTRUECUT_SANITIZE=OFF >/dev/null
cmake --build build -j"$(nproc)" --target truecut pos_loop
# Until the closed-loop demo exists: the soft-CNC loop on the built-in circle example.
build/truecut run examples/circle/circle.hal --ini examples/circle/circle.ini --time 4 --out out/circle
echo "trace: out/circle/trace.csv"
