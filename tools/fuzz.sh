#!/usr/bin/env bash
# libFuzzer on every reader (docs/reliability.md, "Fuzzing").
#   tools/fuzz.sh [SECONDS] [TARGET...]        each target SECONDS of wall time (default 60)
#   tools/fuzz.sh --cpu 3600 [TARGET...]       each target an hour of its own CPU time, however
#                                              busy the machine (stopped with SIGINT, as a user would)
# Builds build-fuzz/ (or $TRUECUT_FUZZ_DIR) with clang (-fsanitize=fuzzer,address,undefined),
# seeds each target from the repository's own files (fuzz/seeds.sh), keeps what it learns in
# build-fuzz/corpus/TARGET, what crashes in build-fuzz/findings/TARGET, and one
# line per run (UTC time, target, CPU s, inputs run, result) in build-fuzz/fuzz-runs.tsv.
# Exit 1 when a target found a crash, a leak or a timeout.
set -euo pipefail
cd "$(dirname "$0")/.."
cpu_mode=0
if [ "${1:-}" = "--cpu" ]; then
  cpu_mode=1
  shift
fi
seconds=${1:-60}
shift || true
all=(gcode rewrite expression tool_table parameter_file mesh field_file ini hal machine_json part_json recording)
targets=("${@:-${all[@]}}")
[ ${#targets[@]} -eq 0 ] && targets=("${all[@]}")
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is not installed (apt install clang libclang-rt-14-dev)" >&2; exit 2; }
dir=${TRUECUT_FUZZ_DIR:-build-fuzz}
mkdir -p "$dir"
# Two fuzz.sh at once (one per core) build one after the other, not into each other.
(
  flock 9
  CC=clang CXX=clang++ cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTRUECUT_FUZZ=ON \
    -DTRUECUT_BUILD_TESTS=OFF -DTRUECUT_BUILD_BENCH=OFF >/dev/null
  cmake --build "$dir" -j"$(nproc)" --target $(printf 'fuzz_%s ' "${targets[@]}") >/dev/null
) 9>"$dir/.build.lock"

# CPU seconds (user + system) a running process has used so far.
cpu_seconds() {
  local st
  read -r -a st < "/proc/$1/stat" 2>/dev/null || return 1
  echo $(((st[13] + st[14]) / $(getconf CLK_TCK)))
}

status=0
for t in "${targets[@]}"; do
  corpus=$dir/corpus/$t findings=$dir/findings/$t
  mkdir -p "$corpus" "$findings"
  [ -n "$(ls -A "$corpus")" ] || fuzz/seeds.sh "$t" "$corpus" build/truecut
  wall_limit=$seconds
  timeout_s=10
  # libFuzzer's per-input timeout is wall time: a run at nice 19 beside other
  # work may wait seconds for the CPU (an input of 1 s was reported as a
  # 10 s timeout), so with --cpu only a real hang counts.
  ((cpu_mode)) && wall_limit=0 timeout_s=300  # 0: libFuzzer's own clock off; stopped below
  echo "fuzz_$t: ${seconds} s$( ((cpu_mode)) && echo " of CPU")" >&2
  "$dir/fuzz_$t" "$corpus" -max_total_time="$wall_limit" -timeout="$timeout_s" -rss_limit_mb=2048 \
    -max_len=65536 -artifact_prefix="$findings/" -print_final_stats=1 \
    > "$findings/log.txt" 2>&1 &
  pid=$!
  used=0
  while kill -0 "$pid" 2>/dev/null; do
    used=$(cpu_seconds "$pid") || break
    if ((cpu_mode && used >= seconds)); then
      kill -INT "$pid"
      break
    fi
    sleep 2
  done
  rc=0
  wait "$pid" || rc=$?
  # libFuzzer exits 72 when interrupted (SIGINT), after its final statistics.
  if ((rc != 0 && !(cpu_mode && rc == 72))); then
    echo "fuzz_$t: FOUND a problem; see $findings/ (log.txt and the input)" >&2
    result=finding
    status=1
  else
    result=clean
  fi
  runs=$(grep -oE "stat::number_of_executed_units: *[0-9]+" "$findings/log.txt" | grep -oE "[0-9]+$" || echo "?")
  printf '%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$t" "$used" "$runs" "$result" >> "$dir/fuzz-runs.tsv"
  grep -E "stat::number_of_executed_units|cov:" "$findings/log.txt" | tail -2 >&2 || true
done
exit $status
