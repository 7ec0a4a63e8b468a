#!/usr/bin/env bash
# The table of the sources' methods in docs/results.md, regenerated: the
# closed-loop demo with the sources' own recipes beside the project's
# (truecut demo --paper) on the implant at scanner sigma 5, 20 and 50 um and
# on benchmark004 at 20 um, into out/papers, then the table on stdout.
# About 15 minutes on a 2-core machine (benchmark004 is most of it).
# Run tools/demo.sh once first on a fresh machine (it installs what is missing).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/configure.sh >/dev/null
cmake --build build -j"$(nproc)" --target truecut interp_planner truecut_comp tool_geometry \
      machine_joints cutting
results=()
for sigma in 5 20 50; do
  build/truecut demo --part implant --paper --sigma-um "$sigma" --out "out/papers/implant_s$sigma" >&2
  results+=("out/papers/implant_s$sigma/results.json")
done
build/truecut demo --part benchmark004 --paper --out out/papers/benchmark004_s20 >&2
results+=(out/papers/benchmark004_s20/results.json)
tools/paper_table.py "${results[@]}"
