#!/usr/bin/env bash
# Closing the twin's gap on the impact law (docs/resolved.md): the impact
# law identified on the struck cell in place, in the resolved wall (force on
# the boulder against its indentation of the struck cell, the boulder's
# penetration less that cell's own move), instead of on the free-standing
# UCI cell; then the macro twin of the wall run again with it.
#   bench/resolved/in_place.sh [--out DIR]
# Needs bench/resolved/run.sh's runs in DIR: it fits on the resolved wall of
# floor_10_m_s and compares with the other run of the same wall,
# centre_10_m_s (two equally valid runs: the law is not judged on the curve
# it was fitted to). bench/resolved/table.py then adds its row.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$root/results/speed_error
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
gabion=${GABION:-$root/build/gabion}
fit_from=$out/floor_10_m_s/result.h5
twin=$out/centre_10_m_s/macro_twin/case.json
[ -f "$fit_from" ] && [ -f "$twin" ] || { echo "run bench/resolved/run.sh first" >&2; exit 2; }
dir=$out/in_place
mkdir -p "$dir"
# The pipeline's laws with the impact law of material "front" fitted anew;
# no lock-up within the indentation the wall shows (half the edge).
cat >"$dir/fit.json" <<JSON
{"format": "gabion.case/1", "kind": "fit", "seed": 1,
 "material": {"name": "front"},
 "base_law": {"file": "$root/results/pipeline/law.json", "material": "front"},
 "lockup": {"strain": 0.5},
 "impact": {"models": ["elastic_perfectly_plastic", "bilinear"],
            "curves": [{"file": "$fit_from", "path": "cyclic", "velocity_m_s": 10,
                        "x_dataset": "/curves/impact/indentation_m", "y_dataset": "/curves/impact/force_N"}],
            "bounds": {"stiffness_N_m": [1e5, 1e9], "yield_force_N": [1e3, 1e6], "hardening_stiffness_N_m": [0, 1e7]}}}
JSON
"$gabion" run "$dir/fit.json" -q -o "$dir/fit" >"$dir/fit.log" 2>&1 || { tail -n 3 "$dir/fit.log" >&2; exit 1; }
"$gabion" run "$twin" --law "$dir/fit/law.json" -q -o "$dir/twin" >"$dir/twin.log" 2>&1 || { tail -n 3 "$dir/twin.log" >&2; exit 1; }
python3 - "$dir" <<'PY'
import json, sys
d = sys.argv[1]
law = json.load(open(f"{d}/fit/law.json"))["materials"]["front"]["impact"]
print("impact law fitted in the wall:", json.dumps(law))
PY
