#!/bin/sh
# Closed loop of `truecut field` variants on a finished demo folder: for each
# variant (a name and extra `truecut field` options), build the field from
# the demo's scan of the uncompensated part, machine part 2 with it and
# probe it with the demo's CMM settings and with a dense noiseless CMM (the
# truth). Used for benchmark004 in docs/offline.md ("Noise: compensate only
# what is measured").
#
#   bench/field_variants.sh out/b4/benchmark004 TRUECUT DEXEL_MM CMM_SPACING_MM \
#       NAME "OPTIONS" [NAME "OPTIONS" ...]
set -e
dir=$1 tc=$2 dexel=$3 spacing=$4
shift 4
cd "$dir"
while [ $# -ge 2 ]; do
  name=$1 opts=$2
  shift 2
  # shellcheck disable=SC2086
  "$tc" field part/nominal.stl uncompensated/scan_mesh.ply --program part/program.ngc \
    --tools part/tools.tbl --part part/part.json --resolution 1 --edge-exclusion 0.2 \
    --out "variant_$name/field" $opts > "variant_$name.field.log" 2>&1
  "$tc" run part/machine.json part/program.ngc --out "variant_$name/run" --dexel-spacing "$dexel" \
    --nominal part/nominal.stl --part part/part.json --tools part/tools.tbl \
    --field "variant_$name/field/field.tcf" > "variant_$name.run.log" 2>&1
  "$tc" cmm "variant_$name/run/machined.stl" --nominal part/nominal.stl --part part/part.json \
    --spacing "$spacing" --sigma-um 0 --out "variant_$name/cmm_truth.csv" > "variant_$name.cmm.log" 2>&1
  echo "== $name ($opts)"
  cat "variant_$name.cmm.log"
done
