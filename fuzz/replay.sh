#!/usr/bin/env bash
# fuzz/replay.sh REPLAY TARGET TRUECUT: ctest's replay of a fuzzing target's
# seeds (fuzz/seeds.sh) through REPLAY, its fuzz_replay_TARGET executable.
set -euo pipefail
replay=$1 target=$2 truecut=$3
seeds=$(mktemp -d)
trap 'rm -rf "$seeds"' EXIT
"$(dirname "$0")/seeds.sh" "$target" "$seeds" "$truecut"
"$replay" "$seeds"
