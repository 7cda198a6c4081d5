#!/usr/bin/env bash
# The cell's own rate effect (docs/resolved.md, "The back face: the cell's
# momentum flux"): the pipeline's confined compression of its cell run again
# at faster plate speeds, then the pipeline's fit case with those curves as
# the axial law's rate curves: the momentum flux c_m r^2 min(1, u / u_a)
# fitted on them with the law from the slow compression held
# (docs/fitting.md, "Momentum flux").
#   bench/resolved/cc_rate.sh [--pipeline DIR] [--out DIR] [--speeds "1 2 3 4"] [--reference 0.1]
# Needs the pipeline's results (README, command 1): DIR/2_cc/case.json, its
# cell, and DIR/3_fit/case.json. The compressions go to 10 % strain
# without unloading, with the netting's real mass (no mass scaling: the
# fill's inertia is what they measure): the reference speed (not fitted,
# the quasi-static curve of the table) and the fast ones; about 80 s on 2
# cores, most of it the reference. Prints the lid and base forces of each
# at 30, 45 and 55 mm of shortening. Writes OUT/cc_rate/cc_<speed>/ and
# OUT/cc_rate/fit/ (law.json, fit_momentum_flux.png). Then the pipeline's CC
# test once more, unloaded past the densification onset (at 8 % strain,
# OUT/cc_rate/cc_cycle/), and the axial law fitted on that cycle with the
# model that keeps part of the compaction offered (densifying_plastic) and
# the same fast curves: OUT/cc_rate/fit_cycle/, the cell's axial law from
# its compressions alone (about 20 s more).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
pipeline=$root/results/pipeline
out=$root/results/speed_error
speeds="1 2 3 4"
reference=0.1
while [ $# -gt 0 ]; do
  case $1 in
    --pipeline) pipeline=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --speeds) speeds=$2; shift 2 ;;
    --reference) reference=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
gabion=${GABION:-$root/build/gabion}
curves=${CURVES:-$root/build/bench/bench_curves}
[ -f "$pipeline/2_cc/case.json" ] && [ -f "$pipeline/3_fit/case.json" ] || {
  echo "no pipeline results in $pipeline: run the README's command 1 first" >&2
  exit 2
}
mkdir -p "$out/cc_rate"
dir=$(cd "$out/cc_rate" && pwd)
# Runs gabion on CASE into DIR/NAME, its answer in DIR/NAME.log; on failure
# shows the log's end and stops.
run() {  # NAME CASE [gabion run options...]
  local name=$1 case=$2
  shift 2
  "$gabion" run "$case" "$@" -q -o "$dir/$name" >"$dir/$name.log" 2>&1 || {
    tail -n 3 "$dir/$name.log" >&2
    exit 1
  }
}
for v in $reference $speeds; do
  python3 - "$pipeline/2_cc/case.json" "$dir/cc_$v.json" "$v" <<'PY'
import json, sys
case = json.load(open(sys.argv[1]))
v = float(sys.argv[3])
case["description"] = f"The pipeline's confined compression at {v:g} m/s (bench/resolved/cc_rate.sh)"
case["loading"] = {"velocity_m_s": v, "strain": 0.1, "unload_at_strain": []}
case["netting_mass_scale"] = 1
json.dump(case, open(sys.argv[2], "w"), indent=1)
PY
  run "cc_$v" "$dir/cc_$v.json" --threads 2
  echo "$v m/s: $(grep '^micro.cc' "$dir/cc_$v.log")"
done
if [ -x "$curves" ]; then
  python3 - "$curves" "$dir" $reference $speeds <<'PY'
import subprocess, sys
curves, d, speeds = sys.argv[1], sys.argv[2], sys.argv[3:]
def at(v, dataset, u):
    out = subprocess.run([curves, "at", f"{d}/cc_{v}/result.h5", "/curves/axial/displacement_m",
                          "/curves/axial/" + dataset, str(u)], capture_output=True, text=True, check=True)
    return float(out.stdout) / 1e3
print("| plate speed m/s | lid force at 30 / 45 / 55 mm, kN | base force at 30 / 45 / 55 mm, kN |")
print("|---|---|---|")
for v in speeds:
    cells = [" / ".join(f"{at(v, ds, u):.1f}" for u in (0.030, 0.045, 0.055)) for ds in ("force_N", "base_force_N")]
    print(f"| {v} | {cells[0]} | {cells[1]} |")
PY
fi
python3 - "$pipeline/3_fit/case.json" "$dir/fit.json" "$dir" $speeds <<'PY'
import json, sys
case = json.load(open(sys.argv[1]))
d = sys.argv[3]
case["description"] = "The pipeline's fit case with the axial law's momentum flux from faster compressions (bench/resolved/cc_rate.sh)"
case["axial"]["rate_curves"] = [{"file": f"{d}/cc_{v}/result.h5"} for v in sys.argv[4:]]
json.dump(case, open(sys.argv[2], "w"), indent=1)
PY
run fit "$dir/fit.json"
grep -E '^fit: (axial|momentum_flux)' "$dir/fit.log"
echo "law: $dir/fit/law.json; chart: $dir/fit/fit_momentum_flux.png"
# The cycle past the onset, and the axial law fitted on it.
run cc_cycle "$pipeline/2_cc/case.json" --set 'loading.unload_at_strain=[0.08]' --threads 2
python3 - "$dir/fit.json" "$dir/fit_cycle.json" "$dir/cc_cycle/result.h5" <<'PY'
import json, sys
case = json.load(open(sys.argv[1]))
case["description"] = "The axial law fitted on a CC cycle past the densification onset, with its momentum flux (bench/resolved/cc_rate.sh)"
case["axial"]["curves"] = [{"file": sys.argv[3], "path": "cyclic"}]
case["axial"]["models"] = ["densifying", "densifying_plastic"]
json.dump(case, open(sys.argv[2], "w"), indent=1)
PY
run fit_cycle "$dir/fit_cycle.json"
grep -E '^fit: (axial|momentum_flux)' "$dir/fit_cycle.log"
echo "law: $dir/fit_cycle/law.json"
