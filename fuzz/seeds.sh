#!/usr/bin/env bash
# fuzz/seeds.sh TARGET FOLDER [TRUECUT]: copies the repository's own inputs
# for a fuzzing target into FOLDER: examples, test data, fuzz/seeds (small
# meshes of every format) and fuzz/regressions/TARGET (past findings).
# tools/fuzz.sh seeds its corpus with them; ctest replays them
# (fuzz/CMakeLists.txt). TRUECUT, the truecut executable, writes a real
# part.json for part_json (default build/truecut, if built).
set -euo pipefail
target=$1
mkdir -p "$2"
d=$(realpath "$2") truecut=$(realpath -m "${3:-build/truecut}")
cd "$(dirname "$0")/.."
case $target in
  rewrite) cp fuzz/seeds/rewrite/*.ngc "$d" ;;
  gcode|expression) find examples tests/interp/corpus -name '*.ngc' -size -64k -exec cp -t "$d" {} + 2>/dev/null || true ;;
  tool_table) find examples tests -name '*.tbl' -exec cp -t "$d" {} + 2>/dev/null || true ;;
  parameter_file) find examples tests -name '*.var' -exec cp -t "$d" {} + 2>/dev/null || true ;;
  mesh) find fuzz/seeds examples tests -name '*.stl' -size -256k -o -name '*.ply' -size -256k -o -name '*.xyz' -size -256k | head -50 |
          while read -r f; do case $f in *.stl) p=0;; *.ply) p=1;; *) p=2;; esac
            { printf "\\x$(printf %02x $p)"; cat "$f"; } > "$d/$(basename "$f")"; done ;;
  field_file) find examples tests -name '*.tcf' -size -256k -exec cp -t "$d" {} + 2>/dev/null || true ;;
  ini) find examples sim -name '*.ini' -exec cp -t "$d" {} + 2>/dev/null || true ;;
  hal) find examples sim -name '*.hal' -exec cp -t "$d" {} + 2>/dev/null || true ;;
  machine_json) cp examples/machines/*.json "$d" ;;
  part_json) if [ -x "$truecut" ]; then
               out=$(mktemp -d)
               "$truecut" part implant --out "$out" >/dev/null && cp "$out/part.json" "$d"
               rm -rf "$out"
             fi ;;
  recording) find data examples tests -name '*.csv' -size -256k | head -50 | xargs -r cp -t "$d" ;;
  *) echo "fuzz/seeds.sh: no target '$target'" >&2; exit 2 ;;
esac
# Inputs that once crashed a reader (docs/reliability.md, "Fuzzing"), as the
# target reads them.
[ -d "fuzz/regressions/$target" ] && cp fuzz/regressions/"$target"/* "$d"
[ -n "$(ls -A "$d")" ] || printf 'x' > "$d/empty-seed"
