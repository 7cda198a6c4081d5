#!/usr/bin/env bash
# The resolved wall against its macro twin and its hybrids (docs/resolved.md,
# docs/speed-vs-error.md): cases/macro_resolved.json (the 2 x 3 x 2 wall of
# the pipeline's cell, hybrids within 0, 0.25 and 0.5 m of the aim) at
# several boulder speeds and one off-centre aim, and the resolved wall once
# more at a step 5 % shorter (the floor of any error), then one table.
#   bench/resolved/run.sh [--out DIR] [--threads N] [--speeds "6 8 10 13"] [--set KEY=VALUE ...]
# (--set: passed on to every scenario's macro.resolved case, e.g.
# resolved.settle.until_at_rest=false to strike the walls after a set
# settling, as the runs of results/speed_error_moving in docs/resolved.md)
# Needs the pipeline's cell and laws (README, command 1: results/pipeline).
# A scenario whose summary.json exists is not run again (delete it to rerun).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$root/results/speed_error threads=2 speeds="6 8 10 13" sets=()
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --speeds) speeds=$2; shift 2 ;;
    --set) sets+=(--set "$2"); shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
. "$here/common.sh"
run() {
  local name=$1; shift
  run_once "$name" "$root/cases/macro_resolved.json" ${sets[@]+"${sets[@]}"} "$@"
}
for v in $speeds; do
  run "centre_${v}_m_s" --set boulder.velocity_m_s="$v"
done
# Off centre: the centre of the upper front cell at the wall's side.
run "side_10_m_s" --set boulder.velocity_m_s=10 --set boulder.aim_point_m=[0.25,0.75]
# The floor: the centred 10 m/s wall again at a step 5 % shorter, as valid a
# run as the first (a granular impact is chaotic: two valid runs differ).
ref=$out/centre_10_m_s/resolved
if [ -f "$ref/summary.json" ] && [ ! -f "$out/floor_10_m_s/summary.json" ]; then
  echo "== floor_10_m_s" >&2
  dt=$(python3 -c "import json, sys; print(0.95 * json.load(open(sys.argv[1]))['dt_s'])" "$ref/summary.json")
  "$gabion" run "$ref/case.json" --threads "$threads" -q -o "$out/floor_10_m_s" --set run.dt_s="$dt" \
    >"$out/floor_10_m_s.log" 2>&1 || echo "   floor_10_m_s failed: $(tail -n 1 "$out/floor_10_m_s.log")" >&2
fi
python3 "$here/table.py" "$out" "$curves"
