#!/usr/bin/env bash
# The README's first command: install what is missing, build, run the main
# job — the closed-loop demo on all three parts (machine with hidden physics,
# scan, correction field, real-time and G-code compensation, CMM), writing
# out/demo/report.html and out/demo/results.json. Extra arguments go to
# `truecut demo` (e.g. --part all, --sigma-um 50).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
# Same folder and options as tools/test.sh (tools/configure.sh), so switching
# between the two rebuilds nothing: the tests then add only their own targets.
tools/configure.sh >/dev/null
cmake --build build -j"$(nproc)" --target truecut interp_planner truecut_comp tool_geometry \
      machine_joints cutting
# All three parts unless the caller names one (`tools/demo.sh --part implant`).
case " $* " in
  *" --part "*) build/truecut demo --out out/demo "$@" ;;
  *) build/truecut demo --part all --out out/demo "$@" ;;
esac
