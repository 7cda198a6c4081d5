#!/usr/bin/env bash
# The resolved wall against its macro twin and its hybrids (docs/resolved.md,
# docs/speed-vs-error.md): cases/macro_resolved.json (the 2 x 3 x 2 wall of
# the pipeline's cell, hybrids within 0, 0.25 and 0.5 m of the aim) at
# several boulder speeds and one off-centre aim, then one table.
#   bench/resolved/run.sh [--out DIR] [--threads N] [--speeds "6 10 13"]
# Needs the pipeline's cell and laws (README, command 1: results/pipeline).
# A scenario whose summary.json exists is not run again (delete it to rerun).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$root/results/speed_error threads=2 speeds="6 10 13"
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --speeds) speeds=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
gabion=${GABION:-$root/build/gabion}
[ -x "$gabion" ] || { echo "build first (scripts/build.sh)" >&2; exit 2; }
[ -f "$root/results/pipeline/law.json" ] || { echo "run the pipeline first (README, command 1)" >&2; exit 2; }
mkdir -p "$out"
run() {
  local name=$1; shift
  [ -f "$out/$name/summary.json" ] && return 0
  echo "== $name" >&2
  "$gabion" run "$root/cases/macro_resolved.json" --threads "$threads" -q -o "$out/$name" "$@" >"$out/$name.log" 2>&1 ||
    echo "   $name failed: $(tail -n 1 "$out/$name.log")" >&2
}
for v in $speeds; do
  run "centre_${v}_m_s" --set boulder.velocity_m_s="$v"
done
# Off centre: the centre of the upper front cell at the wall's side.
run "side_10_m_s" --set boulder.velocity_m_s=10 --set boulder.aim_point_m=[0.25,0.75]
python3 "$here/table.py" "$out"
