#!/usr/bin/env bash
# LinuxCNC's own interpreter regression programs through rs274 and truecut.
#
#   tools/linuxcnc-regression.sh [options] DIR
#
# DIR is laid out like tests/interp of a LinuxCNC source checkout
# (linuxcnc/tests/interp): one folder per test, with its .ngc programs, a
# test.sh that shows how rs274 runs them (-t tool table, -i INI, -v parameter
# file), tool tables, INIs and parameter files. Each program runs through
# LinuxCNC's standalone interpreter rs274 as its test.sh runs it, and through
# `truecut canon` with the matching options (tool table and parameter file in
# the INI's [TRAJ]LINEAR_UNITS, inch without an INI, as rs274 reads them);
# the two listings are compared call by call by the rs274 oracle's
# comparison (tests/interp/rs274_compare.hpp, built as rs274_compare).
#
# One line per program: agree; both refuse (on the same line or not);
# truecut refuses (its message); rs274 refuses but truecut runs; differ
# (the first differing call). Tests that need what no standalone rs274 has
# (a running LinuxCNC, HAL, a UI script, Python remaps) are listed as such
# and not run. Totals at the end.
#
# options:
#   --truecut PATH   the truecut executable (default build/truecut)
#   --compare PATH   rs274_compare (default build/rs274_compare)
#   --rs274 PATH     LinuxCNC's rs274 (default: rs274 on PATH)
#   --keep DIR       keep both listings of every run in DIR
#
# Nothing of LinuxCNC is in this repository: the programs are read from DIR
# at run time. Exit 0 once every program has been classified.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
truecut=$root/build/truecut
compare=$root/build/rs274_compare
rs274=$(command -v rs274 || true)
keep=
while [ $# -gt 1 ]; do
  case $1 in
    --truecut) truecut=$2; shift 2 ;;
    --compare) compare=$2; shift 2 ;;
    --rs274) rs274=$2; shift 2 ;;
    --keep) keep=$2; shift 2 ;;
    *) break ;;
  esac
done
if [ $# -ne 1 ] || [ ! -d "$1" ]; then
  sed -n '2,/^set -u/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2
  exit 2
fi
dir=$(cd "$1" && pwd)
for tool in "$truecut" "$compare" "$rs274"; do
  if [ -z "$tool" ] || [ ! -x "$tool" ]; then
    echo "linuxcnc-regression: missing executable '${tool:-rs274}' (build the targets truecut and rs274_compare; install linuxcnc-uspace for rs274)" >&2
    exit 2
  fi
done
# The programs run in their own folders: relative paths given here would
# no longer name the executables there.
truecut=$(realpath "$truecut")
compare=$(realpath "$compare")
rs274=$(realpath "$rs274")
[ -n "$keep" ] && mkdir -p "$keep"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/home"

declare -A total=()
count() { total[$1]=$((${total[$1]:-0} + 1)); }

# The [RS274NGC] keys an INI sets (truecut has no INI: they are named when
# the outcome is not agreement).
ini_keys() {
  awk -F= '/^\s*\[/{s=$0} s ~ /RS274NGC/ && /=/ {gsub(/[ \t]/, "", $1); if ($1 != "SUBROUTINE_PATH") printf "%s%s", sep, $1; sep=","}' "$1"
}

# The units rs274 reads tool tables and parameter files in: the INI's
# [TRAJ]LINEAR_UNITS, inch without one.
ini_units() {
  local u=inch
  if [ -n "$1" ] && awk '/^\s*\[/{s=$0} s ~ /TRAJ/ && /^\s*LINEAR_UNITS/' "$1" | grep -qiE '=\s*(mm|metric|millimet)'; then
    u=mm
  fi
  echo $u
}

# What a test needs beyond a standalone rs274, or nothing.
needs_of() {
  local t=$1
  if [ -e "$t/test-ui.py" ] || ls "$t"/*.hal > /dev/null 2>&1 ||
    grep -qE '(^|[^-a-z_./])(linuxcnc|halrun)( |$)|python[23]? +[^ <]*\.py' "$t/test.sh" 2> /dev/null; then
    echo "a running LinuxCNC (task, HAL or a UI script)"
  elif grep -qiE '^\s*(\[PYTHON\]|REMAP\s*=)' "$t"/*.ini 2> /dev/null || ls "$t"/*.py > /dev/null 2>&1; then
    echo "embedded Python or remaps"
  elif [ -e "$t/use-rs274.cc" ] || { [ -e "$t/test.sh" ] && ! ls "$t"/*.ngc > /dev/null 2>&1 && ! grep -q 'rs274' "$t/test.sh"; }; then
    echo "no program of its own (builds or loads LinuxCNC code)"
  fi
}

# The rs274 runs of a test: "PROGRAM|INI|TOOLS|VARS" lines, from the
# literal `rs274 ... PROGRAM.ngc` calls of its test.sh, or, for a test.sh
# without one (or none), every program of the folder with test.ini and
# test.tbl when present.
runs_of() {
  local t=$1 found=0 line args prog ini tbl var
  if [ -f "$t/test.sh" ]; then
    while IFS= read -r line; do
      args=$(sed -E 's/.*(^|[^-a-zA-Z_./])rs274 +//; s/[|;>&].*//; s/2$//' <<< "$line")
      prog='' ini='' tbl='' var=''
      set -- $args
      while [ $# -gt 0 ]; do
        case $1 in
          -i) ini=${2:-}; shift ;;
          -t) tbl=${2:-}; shift ;;
          -v) var=${2:-}; shift ;;
          -n) shift ;;
          -*) ;;
          *) prog=$1 ;;
        esac
        shift
      done
      prog=${prog//\"/}
      # A program named by a variable (a loop over the folder) is not a run.
      case $prog in *.ngc | *.NGC) ;; *) continue ;; esac
      case $prog in *'$'* | *%*) continue ;; esac
      echo "$prog|$ini|$tbl|$var"
      found=1
    done < <(sed -e ':a' -e '/\\$/N; s/\\\n//; ta' "$t/test.sh" | grep -E '(^|[^-a-zA-Z_./])rs274 ' | grep -v '^\s*#')
  fi
  [ $found = 1 ] && return
  ini='' tbl=''
  [ -f "$t/test.ini" ] && ini=test.ini
  [ -f "$t/test.tbl" ] && tbl=test.tbl
  for prog in "$t"/*.ngc; do
    [ -f "$prog" ] && echo "$(basename "$prog")|$ini|$tbl|"
  done
}

# A block as rs274 and truecut show it, for comparing where they stop.
squeeze() { tr -d ' \t\r' | tr 'A-Z' 'a-z'; }

run_one() {
  local t=$1 name=$2 prog=$3 ini=$4 tbl=$5 var=$6
  local units rs_args=() tc_args=() note=
  units=$(ini_units "${ini:+$t/$ini}")
  [ -n "$ini" ] && rs_args+=(-i "$ini")
  if [ -n "$tbl" ]; then
    rs_args+=(-t "$tbl")
    # A missing table is an empty one to rs274.
    [ -f "$t/$tbl" ] && tc_args+=(--tool-table "$tbl" --tool-units "$units")
  fi
  if [ -n "$var" ]; then
    # rs274 writes its parameter file back: it gets a copy. A file that
    # test.sh makes from a template is made from it here.
    local source=$t/$var
    [ -f "$source" ] || source=$t/$var.template
    if [ -f "$source" ]; then
      cp "$source" "$work/params.var"
      rs_args+=(-v "$work/params.var")
      tc_args+=(--var-file "$source")
    fi
  fi
  # The machine's units: where rs274 keeps the offset parameters.
  tc_args+=(--var-units "$units")
  (cd "$t" && HOME=$work/home timeout 60 "$rs274" -g "${rs_args[@]}" "$prog" > "$work/rs274.out" 2> "$work/rs274.err")
  local rs_rc=$?
  (cd "$t" && timeout 60 "$truecut" canon --quiet --decimals 8 --b-axis "${tc_args[@]}" "$prog" > "$work/truecut.out" 2> "$work/truecut.err")
  local tc_rc=$?
  if [ -n "$keep" ]; then
    local k=$keep/${name//\//_}
    cp "$work/rs274.out" "$k.rs274"
    cp "$work/truecut.out" "$k.truecut"
  fi
  [ -n "$ini" ] && [ -n "$(ini_keys "$t/$ini")" ] && note=" [INI sets $(ini_keys "$t/$ini"); truecut has no INI]"
  local rs_msg tc_msg
  rs_msg=$(grep -v '^executing$' "$work/rs274.err" | tail -n 2 | head -n 1)
  tc_msg=$(head -n 1 "$work/truecut.err")
  if [ $rs_rc = 0 ] && [ $tc_rc = 0 ]; then
    local diff
    # rs274 ends with one ON_RESET more without an INI than with one: its
    # shutdown, not the program's; the trailing ON_RESETs are not compared.
    local f
    for f in rs274 truecut; do
      tac "$work/$f.out" | awk 'body || !/ ON_RESET\(\)$/ { body = 1; print }' | tac > "$work/$f.cmp"
    done
    # The test's own filter on rs274's output (`| sed 's/-0\.0000/0.0000/g'`:
    # the sign of a zero that rounding leaves is not part of the result) is
    # applied to both listings, as LinuxCNC's harness applies it to its own.
    local script
    while IFS= read -r script; do
      [[ $script == s/*/*/* ]] || continue
      sed -i -e "$script" "$work/rs274.cmp" "$work/truecut.cmp"
    done < <(sed -e ':a' -e '/\\$/N; s/\\\n//; ta' "$t/test.sh" 2>/dev/null |
      grep -E '(^|[^-a-zA-Z_./])rs274 ' | grep -v '^\s*#' |
      grep -oE "\| *sed +(-e +)?'[^']*'" | sed -E "s/^\| *sed +(-e +)?'//; s/'$//" | sort -u)
    if diff=$("$compare" "$work/rs274.cmp" "$work/truecut.cmp"); then
      echo "$name: agree"
      count agree
    else
      echo "$name: differ: $diff$note"
      count differ
    fi
  elif [ $rs_rc != 0 ] && [ $tc_rc != 0 ]; then
    # rs274 names the block it stops on; truecut its file and line.
    local rs_block tc_block='' file line
    rs_block=$(grep -v '^executing$' "$work/rs274.err" | tail -n 1)
    if [[ $tc_msg =~ ^(.+):([0-9]+):[0-9]+:\  ]]; then
      file=${BASH_REMATCH[1]} line=${BASH_REMATCH[2]}
      [ -f "$t/$file" ] && file=$t/$file
      [ -f "$file" ] && tc_block=$(sed -n "${line}p" "$file")
    fi
    if [ -n "$tc_block" ] && [ "$(squeeze <<< "$rs_block")" = "$(squeeze <<< "$tc_block")" ]; then
      echo "$name: both refuse, same line (rs274: $rs_msg | truecut: $tc_msg)"
      count both_refuse_same
    else
      echo "$name: both refuse, not the same line (rs274: $rs_msg at '$rs_block' | truecut: $tc_msg)"
      count both_refuse_other
    fi
  elif [ $tc_rc != 0 ]; then
    echo "$name: truecut refuses: $tc_msg$note"
    count truecut_refuses
  else
    echo "$name: rs274 refuses ($rs_msg) but truecut runs$note"
    count rs274_refuses
  fi
}

# The test folders: those with a test.sh, an expected output or programs,
# less subroutine folders (a folder inside a test folder).
test_folders() {
  find "$dir" -type f \( -name test.sh -o -name expected -o -name test -o -name '*.ngc' \) -printf '%h\n' |
    sort -u | awk '{ for (i = 1; i <= n; i++) if (index($0, kept[i] "/") == 1) next; kept[++n] = $0; print }'
}

while IFS= read -r t; do
  rel=${t#"$dir"/}
  needs=$(needs_of "$t")
  if [ -n "$needs" ]; then
    echo "$rel: needs $needs: not run"
    count needs
    continue
  fi
  while IFS='|' read -r prog ini tbl var; do
    [ -f "$t/$prog" ] || { echo "$rel/$prog: program missing from the folder"; count missing; continue; }
    opts=
    [ -n "$ini" ] && opts+=" -i $ini"
    [ -n "$var" ] && opts+=" -v $var"
    run_one "$t" "$rel/$prog${opts:+ [${opts# }]}" "$prog" "$ini" "$tbl" "$var"
  done < <(runs_of "$t" | awk '!seen[$0]++')
done < <(test_folders)

echo
echo "agree: ${total[agree]:-0}"
echo "both refuse, same line: ${total[both_refuse_same]:-0}"
echo "both refuse, not the same line: ${total[both_refuse_other]:-0}"
echo "truecut refuses: ${total[truecut_refuses]:-0}"
echo "rs274 refuses, truecut runs: ${total[rs274_refuses]:-0}"
echo "differ: ${total[differ]:-0}"
echo "tests not run (need more than a standalone rs274): ${total[needs]:-0}"
[ -n "${total[missing]:-}" ] && echo "programs missing: ${total[missing]}"
exit 0
