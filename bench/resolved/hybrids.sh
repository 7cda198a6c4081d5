#!/usr/bin/env bash
# The hybrid within 0.25 m of bench/resolved/run.sh's scenarios, changed one
# way at a time (docs/resolved.md, What the hybrids buy), then one table:
#   OUT/below/<scenario>          its resolved cells and the cells below them
#                                 (resolve.below "cells"), at 10 and 6 m/s on
#                                 the centre and 10 m/s on the side;
#   OUT/hybrid_more/floor_0.25    at 10 m/s on the centre again at a step 5 %
#                                 shorter (the hybrid's own floor);
#   OUT/hybrid_more/whole_0.25    through the depth (resolve.depth "whole");
#   OUT/hybrid_more/in_place_law_0.25
#                                 its macro part with the laws identified in
#                                 the wall (in_place.sh's fit_flux/law.json).
#   bench/resolved/hybrids.sh [--out DIR] [--threads N]
# About 15 minutes on 2 cores. Needs bench/resolved/run.sh's scenarios (their
# hybrid_1/case.json) and, for the last run, in_place.sh's law.
# A run whose summary.json exists is not run again (delete it to rerun);
# one stopped by SIGTERM or Ctrl-C (its summary "interrupted") is resumed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$root/results/speed_error threads=2
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
. "$here/common.sh"
for s in centre_10_m_s centre_6_m_s side_10_m_s; do
  h=$out/$s/hybrid_1/case.json
  [ -f "$h" ] || { echo "no $h: run bench/resolved/run.sh first" >&2; exit 2; }
  run_once "below/$s" "$h" --set resolve.below=cells
done
h=$out/centre_10_m_s/hybrid_1
dt=$(python3 -c "import json, sys; print(0.95 * json.load(open(sys.argv[1]))['dt_s'])" "$h/summary.json")
run_once hybrid_more/floor_0.25 "$h/case.json" --set resolve.run.dt_s="$dt"
run_once hybrid_more/whole_0.25 "$h/case.json" --set resolve.depth=whole
law=$out/in_place/fit_flux/law.json
if [ -f "$law" ]; then
  run_once hybrid_more/in_place_law_0.25 "$h/case.json" --law "$law"
else
  echo "no $law (bench/resolved/in_place.sh after cc_rate.sh): hybrid_more/in_place_law_0.25 not run" >&2
fi
python3 "$here/table.py" --hybrids "$out"
