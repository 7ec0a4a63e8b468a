#!/usr/bin/env bash
# The README's first command: install what is missing, build, run the main job.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTRUECUT_BUILD_TESTS=OFF >/dev/null
cmake --build build -j"$(nproc)" --target truecut pos_loop
# Until the closed-loop demo exists: the soft-CNC loop on the built-in circle example.
build/truecut run examples/circle/circle.hal --ini examples/circle/circle.ini --time 4 --out out/circle
echo "trace: out/circle/trace.csv"
