#!/usr/bin/env bash
# libFuzzer on every reader (docs/reliability.md, "Fuzzing").
#   tools/fuzz.sh [SECONDS] [TARGET...]   each target SECONDS (default 60)
#   tools/fuzz.sh 3600                    the hour per reader the issue asks for
# Builds build-fuzz/ with clang (-fsanitize=fuzzer,address,undefined), seeds
# each target from the repository's own files, keeps what it learns in
# build-fuzz/corpus/TARGET and what crashes in build-fuzz/findings/TARGET.
# Exit 1 when a target found a crash, a leak or a timeout.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
all=(gcode expression tool_table mesh field_file ini hal machine_json part_json recording)
targets=("${@:-${all[@]}}")
[ ${#targets[@]} -eq 0 ] && targets=("${all[@]}")
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is not installed (apt install clang libclang-rt-14-dev)" >&2; exit 2; }
dir=build-fuzz
CC=clang CXX=clang++ cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTRUECUT_FUZZ=ON \
  -DTRUECUT_BUILD_TESTS=OFF -DTRUECUT_BUILD_BENCH=OFF >/dev/null
cmake --build "$dir" -j"$(nproc)" --target $(printf 'fuzz_%s ' "${targets[@]}") >/dev/null

seed() {  # seed TARGET DIR: copies the repository's own inputs for TARGET
  local d=$2
  case $1 in
    gcode|expression) find examples tests/interp/corpus -name '*.ngc' -size -64k -exec cp -t "$d" {} + 2>/dev/null || true ;;
    tool_table) find examples tests -name '*.tbl' -exec cp -t "$d" {} + 2>/dev/null || true ;;
    mesh) find examples tests -name '*.stl' -size -256k -o -name '*.ply' -size -256k -o -name '*.xyz' -size -256k | head -50 |
            while read -r f; do case $f in *.stl) p=0;; *.ply) p=1;; *) p=2;; esac
              { printf "\\x$(printf %02x $p)"; cat "$f"; } > "$d/$(basename "$f")"; done ;;
    field_file) find examples tests -name '*.tcf' -size -256k -exec cp -t "$d" {} + 2>/dev/null || true ;;
    ini) find examples sim -name '*.ini' -exec cp -t "$d" {} + 2>/dev/null || true ;;
    hal) find examples sim -name '*.hal' -exec cp -t "$d" {} + 2>/dev/null || true ;;
    machine_json) cp examples/machines/*.json "$d" ;;
    part_json) if [ -x build/truecut ]; then  # the demo's build: a real part.json
                 build/truecut part implant --out "$dir/seed-part" >/dev/null && cp "$dir/seed-part/part.json" "$d"
               fi ;;
    recording) find data examples tests -name '*.csv' -size -256k | head -50 | xargs -r cp -t "$d" ;;
  esac
  [ -n "$(ls -A "$d")" ] || printf 'x' > "$d/empty-seed"
}

status=0
for t in "${targets[@]}"; do
  corpus=$dir/corpus/$t findings=$dir/findings/$t
  mkdir -p "$corpus" "$findings"
  [ -n "$(ls -A "$corpus")" ] || seed "$t" "$corpus"
  echo "fuzz_$t: ${seconds} s" >&2
  if ! "$dir/fuzz_$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
       -max_len=65536 -artifact_prefix="$findings/" -print_final_stats=1 \
       > "$findings/log.txt" 2>&1; then
    echo "fuzz_$t: FOUND a problem; see $findings/ (log.txt and the input)" >&2
    status=1
  fi
  grep -E "stat::number_of_executed_units|cov:" "$findings/log.txt" | tail -2 >&2 || true
done
exit $status
